// Inside the protocol layer only: the bit writer/reader every message codec is made of.
// One LSB-first bit stream per message: a value of n bits at a byte boundary is exactly its n/8
// little-endian bytes, so byte-aligned fields (lengths, floats, strings) and packed fields (ids,
// quantized coordinates) use the same two classes and the docs can describe both as "u32", "6 bits".
#pragma once
#include <algorithm>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "protocol/message_types.h"
#include "protocol/stream_context.h"
#include "spm/octahedral_normal.h"
#include "spm/refine_info.h"
#include "spm/split_record.h"

namespace pms::protocol {

// Builds one frame: header bytes reserved first, payload bits after, length patched by finish().
class Writer {
 public:
  explicit Writer(MessageType type);
  void bits(uint64_t value, unsigned n) {  // n <= 64; value must fit (checked by the callers' ids)
    if (n < 64) value &= (uint64_t(1) << n) - 1;
    acc_ |= value << fill_;  // fill_ < 64
    if (fill_ + n < 64) {
      fill_ += n;
      return;
    }
    flush_word();
    acc_ = fill_ ? value >> (64 - fill_) : 0;  // the bits that did not fit
    fill_ = fill_ + n - 64;
  }
  void u8(uint8_t v) { bits(v, 8); }
  void u16(uint16_t v) { bits(v, 16); }
  void u32(uint32_t v) { bits(v, 32); }
  void u64(uint64_t v) { bits(v, 64); }
  void f32(float v);
  // u16 length + bytes; throws pms::Error naming `field` when longer than `max`.
  void string(const std::string& s, size_t max, const char* field);
  // `n` bits of `pool` (LSB-first 64-bit words) from bit `at` on, as if written one by one.
  void bits_from(std::span<const uint64_t> pool, uint64_t at, uint64_t n);
  void align();  // zero bits up to the next byte
  void reserve_payload(size_t bytes) { out_.reserve(kFrameHeaderBytes + bytes); }
  // The payload written so far; only after align().
  std::span<const uint8_t> payload() const { return std::span<const uint8_t>(out_).subspan(kFrameHeaderBytes); }
  uint64_t payload_bits() const { return 8 * uint64_t(out_.size() - kFrameHeaderBytes) + fill_; }
  std::vector<uint8_t> finish();

 private:
  void flush_word() {
    const size_t at = out_.size();
    out_.resize(at + 8);
    for (int i = 0; i < 8; ++i) out_[at + size_t(i)] = uint8_t(acc_ >> (8 * i));
  }

  MessageType type_;
  std::vector<uint8_t> out_;
  uint64_t acc_ = 0;   // pending bits, flushed 64 at a time
  unsigned fill_ = 0;  // < 64 between calls
};

// Reads one payload; every read is bounds-checked and every failure names the message, the item (e.g.
// "packet 12") and the field.
class Reader {
 public:
  Reader(std::span<const uint8_t> payload, MessageType type, uint64_t start_bit = 0)
      : data_(payload), pos_(start_bit), type_(type) {}

  uint64_t bits(unsigned n, const char* field);  // n <= 64
  uint8_t u8(const char* field) { return uint8_t(bits(8, field)); }
  uint16_t u16(const char* field) { return uint16_t(bits(16, field)); }
  uint32_t u32(const char* field) { return uint32_t(bits(32, field)); }
  uint64_t u64(const char* field) { return bits(64, field); }
  float f32(const char* field);         // any bits, NaN included
  float finite_f32(const char* field);  // rejects NaN and infinities
  std::string string(size_t max, const char* field);
  uint64_t bits_left() const { return 8 * uint64_t(data_.size()) - pos_; }
  uint64_t position() const { return pos_; }  // in bits
  std::span<const uint8_t> payload() const { return data_; }
  // Moves on to bit `pos`, which another reader over payload() reached (at most the payload's end).
  void seek(uint64_t pos) { pos_ = std::min<uint64_t>(pos, 8 * uint64_t(data_.size())); }
  // `count` items of at least `min_bits` each must fit in what is left: checked before any allocation.
  void check_count(uint64_t count, uint64_t min_bits, const char* field);
  // Padding bits up to the byte boundary must be zero and nothing may follow: one encoding per message.
  void expect_end();

  void set_item(const char* name, uint64_t index) {
    item_ = name;
    item_index_ = index;
  }
  void clear_item() { item_ = nullptr; }
  [[noreturn]] void fail(ErrorCode code, const char* field, const std::string& what) const;

 private:
  std::span<const uint8_t> data_;
  uint64_t pos_ = 0;  // in bits
  MessageType type_;
  const char* item_ = nullptr;
  uint64_t item_index_ = 0;
};

// RefineInfo at its stored precision (spm/refine_info.h): a flag bit, set when mu = delta = 0 (nothing follows: the
// info decodes as as_sent() says); otherwise 3 lengths of kLengthBits, the cone angle, and the cone axis
// only when there is a cone: 1, 66 or 44 bits (docs/protocol.md). The writer throws for values the
// quantizer never produces, the reader rejects them (the .pms reader does the same).
void write_refine(Writer& w, const RefineInfo& info, const char* field);
uint32_t refine_bits(const RefineInfo& info);
constexpr uint32_t kMinRefineBits = 1;
RefineInfo read_refine(Reader& r, const char* field);

// VSPLITS: frame, flags, count, then the packets (docs/protocol.md).
constexpr uint8_t kFlagFinal = 1;
constexpr uint8_t kFlagAhead = 2;  // VSPLITS only: a batch sent ahead, never final
void write_vsplits_header(Writer& w, uint32_t frame, uint8_t flags, size_t count);
uint8_t vsplits_flags(bool final, bool ahead);  // throws pms::Error for both
// One vsplit packet; throws pms::Error for values the context cannot carry. Not for a context with split
// records (those need the batch's contexts: encode(VSplits)).
void write_packet(Writer& w, const SplitRecord& s, const StreamContext& c);
// A node's id as packets write it (tree-id, depth, path).
void write_id(Writer& w, VertexId v, const StreamContext& c, const char* field);

using pms::decode_normal;
using pms::encode_normal;

// PositionGrid / id widths a decoder accepts; "" when fine, else what is wrong.
std::string check_context(const StreamContext& context);

}  // namespace pms::protocol
