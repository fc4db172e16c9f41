// The bit writer/reader of wire_internal.h and the field codecs shared by several messages.
#include <algorithm>
#include <cmath>
#include <cstring>

#include "common/bit_cast.h"
#include "protocol/message_types.h"
#include "protocol/position_grid.h"
#include "protocol/server_messages.h"
#include "protocol/stream_context.h"
#include "protocol/wire_internal.h"
#include "spm/refine_info.h"

namespace pms::protocol {

Writer::Writer(MessageType type) : type_(type) {
  out_.resize(kFrameHeaderBytes);
  out_[4] = uint8_t(type);
}

void Writer::bits_from(std::span<const uint64_t> pool, uint64_t at, uint64_t n) {
  while (n > 0) {
    const unsigned take = unsigned(std::min<uint64_t>(n, 64));
    const uint64_t word = at / 64;
    const unsigned shift = unsigned(at % 64);
    uint64_t value = pool[word] >> shift;
    if (shift > 0 && shift + take > 64) value |= pool[word + 1] << (64 - shift);
    bits(value, take);
    at += take;
    n -= take;
  }
}

void Writer::f32(float v) { u32(bit_cast<uint32_t>(v)); }

void Writer::string(const std::string& s, size_t max, const char* field) {
  if (s.size() > max || s.size() > UINT16_MAX)
    fail(to_string(type_),
         std::string(field) + " is " + std::to_string(s.size()) + " bytes, at most " + std::to_string(max) + " fit");
  u16(uint16_t(s.size()));
  for (unsigned char c : s) u8(c);
}

void Writer::align() {
  if (fill_ % 8) bits(0, 8 - fill_ % 8);
  for (; fill_ > 0; fill_ -= 8, acc_ >>= 8) out_.push_back(uint8_t(acc_));
}

std::vector<uint8_t> Writer::finish() {
  align();
  const uint64_t size = out_.size() - kFrameHeaderBytes;
  if (size > UINT32_MAX) fail(to_string(type_), "payload of " + std::to_string(size) + " bytes exceeds the u32 length");
  for (int i = 0; i < 4; ++i) out_[i] = uint8_t(size >> (8 * i));
  return std::move(out_);
}

uint64_t Reader::bits(unsigned n, const char* field) {
  if (n > bits_left())
    fail(ErrorCode::bad_message, field,
         "truncated (needs " + std::to_string(n) + " bits, " + std::to_string(bits_left()) + " left)");
  if (n <= 56 && (pos_ >> 3) + 8 <= data_.size()) {  // one unaligned 8-byte load covers offset + n bits
    uint64_t word = 0;
    for (int i = 0; i < 8; ++i) word |= uint64_t(data_[(pos_ >> 3) + size_t(i)]) << (8 * i);
    const uint64_t value = (word >> (pos_ & 7)) & ((uint64_t(1) << n) - 1);
    pos_ += n;
    return value;
  }
  uint64_t value = 0;
  unsigned got = 0;
  while (got < n) {
    const unsigned offset = unsigned(pos_ & 7);
    const unsigned take = std::min(8 - offset, n - got);
    const uint64_t chunk = (uint64_t(data_[pos_ >> 3]) >> offset) & ((1u << take) - 1);
    value |= chunk << got;
    got += take;
    pos_ += take;
  }
  return value;
}

float Reader::f32(const char* field) { return bit_cast<float>(u32(field)); }

float Reader::finite_f32(const char* field) {
  const float v = f32(field);
  if (!std::isfinite(v)) fail(ErrorCode::bad_message, field, "is not finite");
  return v;
}

std::string Reader::string(size_t max, const char* field) {
  const uint16_t size = u16(field);
  if (size > max)
    fail(ErrorCode::bad_message, field, std::to_string(size) + " bytes, at most " + std::to_string(max) + " allowed");
  check_count(size, 8, field);
  std::string s(size, '\0');
  if (pos_ % 8 == 0) {  // the usual case: whole bytes
    std::memcpy(s.data(), data_.data() + pos_ / 8, size);
    pos_ += 8 * uint64_t(size);
  } else {
    for (char& c : s) c = char(u8(field));
  }
  return s;
}

void Reader::check_count(uint64_t count, uint64_t min_bits, const char* field) {
  // Division, not multiplication: a hostile count must not overflow its way past the check.
  if (min_bits > 0 && count > bits_left() / min_bits)
    fail(ErrorCode::bad_message, field,
         "count " + std::to_string(count) + " does not fit in the " + std::to_string(bits_left() / 8) + " bytes left");
}

void Reader::expect_end() {
  const unsigned pad = unsigned((8 - pos_ % 8) % 8);
  if (pad > 0 && bits(pad, "padding") != 0) fail(ErrorCode::bad_message, "padding", "bits are not zero");
  if (pos_ / 8 != data_.size())
    fail(ErrorCode::bad_message, "end", std::to_string(data_.size() - pos_ / 8) + " trailing bytes");
}

void Reader::fail(ErrorCode code, const char* field, const std::string& what) const {
  std::string text = to_string(type_) + ": ";
  if (item_) text += std::string(item_) + " " + std::to_string(item_index_) + ": ";
  text += field;
  text += ": ";
  text += what;
  throw ProtocolError(code, text);
}

// Lengths are half floats whose sign and low kLengthDroppedBits are always 0; the cone axis only
// exists when there is a cone (the angle field's top value means "no cone").
constexpr uint32_t kNoConeOnWire = (1u << kConeAngleBits) - 1;

void write_refine(Writer& w, const RefineInfo& info, const char* field) {
  if (!is_canonical(info)) fail(field, "refinement info is not at the stored precision (pms-format.md RINF)");
  w.bits(never_refines(info), 1);
  if (never_refines(info)) return;
  for (uint16_t half : {info.radius, info.mu, info.delta}) w.bits(half >> kLengthDroppedBits, kLengthBits);
  if (info.cone_angle == kNoCone) {
    w.bits(kNoConeOnWire, kConeAngleBits);
    return;
  }
  w.bits(info.cone_angle, kConeAngleBits);
  for (uint16_t q : {info.cone_x, info.cone_y}) w.bits(uint32_t(int16_t(q) + kAxisSteps), kAxisBits);
}

uint32_t refine_bits(const RefineInfo& info) {
  if (never_refines(info)) return 1;
  return 1 + 3 * kLengthBits + kConeAngleBits + (info.cone_angle == kNoCone ? 0 : 2 * kAxisBits);
}

RefineInfo read_refine(Reader& r, const char* field) {
  if (r.bits(1, field)) return as_sent(RefineInfo{});
  RefineInfo info{};
  for (uint16_t* half : {&info.radius, &info.mu, &info.delta})
    *half = uint16_t(r.bits(kLengthBits, field) << kLengthDroppedBits);
  // The flag is the one encoding of mu = delta = 0, so each info has exactly one.
  if (never_refines(info)) r.fail(ErrorCode::bad_message, field, "mu = delta = 0 sent in full");
  const auto angle = uint32_t(r.bits(kConeAngleBits, field));
  if (angle == kNoConeOnWire) {
    info.cone_angle = kNoCone;
  } else {
    info.cone_angle = uint16_t(angle);
    for (uint16_t* q : {&info.cone_x, &info.cone_y})
      *q = uint16_t(int16_t(int32_t(r.bits(kAxisBits, field)) - kAxisSteps));
  }
  // Lengths above +inf (NaN), an axis coordinate above kAxisSteps or the one unused angle would poison
  // qrefine's comparisons or mean nothing.
  if (!is_canonical(info))
    r.fail(ErrorCode::bad_message, field, "a length is NaN, or the cone axis or angle is out of range");
  return info;
}

std::string check_context(const StreamContext& c) {
  if (c.root_count == 0) return "no roots";
  if (c.tree_id_bits < 1 || c.tree_id_bits > 32)
    return "tree_id_bits " + std::to_string(c.tree_id_bits) + " not in 1..32";
  if (c.tree_id_bits < 32 && ((c.root_count - 1) >> c.tree_id_bits) != 0)
    return "tree_id_bits " + std::to_string(c.tree_id_bits) + " cannot hold " + std::to_string(c.root_count) + " roots";
  if (c.node_id_bits > 63) return "node_id_bits " + std::to_string(c.node_id_bits) + " over 63";
  if (!valid_position_bits(c.grid.bits)) return "position bits " + std::to_string(c.grid.bits) + " not in 1..24 or 32";
  for (int i = 0; i < 3; ++i)
    if (!std::isfinite(c.grid.min[i]) || !std::isfinite(c.grid.max[i]) || !(c.grid.min[i] <= c.grid.max[i]))
      return "bounding box is not finite or min > max";
  if (c.records) {
    if (!c.has_refinement) return "split records carry refinement info";
    if (c.records->has_normals() != c.has_normals || c.records->has_colors() != c.has_colors)
      return "the split record tables carry other attributes than the model's normals and colors";
    if (c.records->root_count() != c.root_count || c.records->max_depth() != c.node_id_bits ||
        c.records->position_bits() != c.grid.bits)
      return "the split record tables are for " + std::to_string(c.records->root_count()) + " roots, depth " +
             std::to_string(c.records->max_depth()) + ", " + std::to_string(c.records->position_bits()) +
             " position bits; the model has " + std::to_string(c.root_count) + ", " + std::to_string(c.node_id_bits) +
             ", " + std::to_string(c.grid.bits);
  }
  return "";
}

}  // namespace pms::protocol
