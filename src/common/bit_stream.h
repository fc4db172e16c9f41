// LSB-first bit streams (docs/protocol.md, "Bit stream"): bit k of the stream is bit k mod 8 of byte
// k div 8, an n-bit field goes least significant bit first. Shared by codecs below the protocol layer
// (spm/split_codec.h); every read is bounds-checked and fails with pms::Error, never reads past the data.
#pragma once
#include <algorithm>
#include <bit>
#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "common/error.h"

namespace pms {

// Up to 8 bytes of `data` from `byte` on, as a little-endian word; bytes past the data read as 0. One load
// where the data has 8 bytes left.
inline uint64_t load_word(std::span<const uint8_t> data, size_t byte) {
  const size_t count = byte < data.size() ? std::min<size_t>(8, data.size() - byte) : 0;
  uint64_t word = 0;
  if (count == 8 && std::endian::native == std::endian::little) {
    std::memcpy(&word, data.data() + byte, 8);
  } else {
    for (size_t i = 0; i < count; ++i) word |= uint64_t(data[byte + i]) << (8 * i);
  }
  return word;
}

class BitWriter {
 public:
  void bits(uint64_t value, unsigned n) {  // n <= 64; bits of value above n are ignored
    // Whole bytes at a time: servers copy records with it (append), and the builder writes every record.
    if (n == 0) return;
    if (n < 64) value &= (uint64_t(1) << n) - 1;
    const unsigned used = unsigned(size_ & 7);
    size_ += n;
    if (used != 0) {
      bytes_.back() |= uint8_t(value << used);
      if (n <= 8 - used) return;
      value >>= 8 - used;
      n -= 8 - used;
    }
    for (;; value >>= 8, n -= 8) {
      bytes_.push_back(uint8_t(value));
      if (n <= 8) return;
    }
  }
  void bit(unsigned b) {
    if ((size_ & 7) == 0) bytes_.push_back(0);
    bytes_.back() |= uint8_t((b & 1) << (size_ & 7));
    ++size_;
  }
  // Bits [begin, end) of `data`, as a BitReader over it would read them.
  void append(std::span<const uint8_t> data, uint64_t begin, uint64_t end) {
    if (end > 8 * uint64_t(data.size()) || begin > end) fail("bit stream", "appending bits outside the data");
    // Geometric growth: an exact reserve per call would copy the whole stream on every append.
    if (const size_t needed = size_t((size_ + (end - begin) + 7) >> 3); needed > bytes_.capacity())
      bytes_.reserve(std::max(needed, 2 * bytes_.capacity()));
    for (unsigned n; begin < end; begin += n) {
      n = unsigned(std::min<uint64_t>(56, end - begin));  // 56 bits from any offset fit in 8 bytes
      bits(load_word(data, size_t(begin >> 3)) >> (begin & 7), n);
    }
  }
  void append(const BitWriter& other) { append(other.bytes_, 0, other.size_); }
  void reserve(uint64_t bits) { bytes_.reserve(size_t((bits + 7) >> 3)); }
  uint64_t size() const { return size_; }  // in bits
  // The bytes written; the last one is padded with zero bits.
  const std::vector<uint8_t>& bytes() const { return bytes_; }
  std::vector<uint8_t> take() && { return std::move(bytes_); }

 private:
  std::vector<uint8_t> bytes_;
  uint64_t size_ = 0;
};

class BitReader {
 public:
  // Reads bits [start, end) of `data`; `what` names the data in error messages.
  BitReader(std::span<const uint8_t> data, uint64_t start, uint64_t end, std::string what)
      : data_(data), pos_(start), end_(end), what_(std::move(what)) {
    if (end > 8 * uint64_t(data.size()) || start > end) fail(what_, "bit range outside the data");
  }
  BitReader(std::span<const uint8_t> data, std::string what)
      : BitReader(data, 0, 8 * uint64_t(data.size()), std::move(what)) {}

  unsigned bit(const char* field) {
    if (pos_ >= end_) fail(what_, std::string(field) + ": truncated");
    const unsigned b = unsigned(data_[pos_ >> 3] >> (pos_ & 7)) & 1;
    ++pos_;
    return b;
  }
  uint64_t bits(unsigned n, const char* field) {
    if (n > 64) fail(what_, std::string(field) + ": a field of " + std::to_string(n) + " bits");
    if (n > end_ - pos_) fail(what_, std::string(field) + ": truncated");
    uint64_t value = 0;
    for (unsigned got = 0; got < n;) {
      const unsigned offset = unsigned(pos_ & 7), take = std::min(n - got, 8 - offset);
      value |= uint64_t((unsigned(data_[pos_ >> 3]) >> offset) & ((1u << take) - 1)) << got;
      got += take;
      pos_ += take;
    }
    return value;
  }
  // The next n <= 32 bits without reading them, for table-driven decoders. Bits past the window's end are
  // what follows it in the data, or 0 past the data: the caller checks what it uses against bits_left().
  uint32_t peek(unsigned n) const {
    return uint32_t((load_word(data_, size_t(pos_ >> 3)) >> (pos_ & 7)) & ((uint64_t(1) << n) - 1));
  }
  void skip(unsigned n, const char* field) {
    if (n > end_ - pos_) fail(what_, std::string(field) + ": truncated");
    pos_ += n;
  }
  uint64_t position() const { return pos_; }
  uint64_t bits_left() const { return end_ - pos_; }
  [[noreturn]] void fail_field(const char* field, const std::string& problem) const {
    fail(what_, std::string(field) + ": " + problem);
  }

 private:
  std::span<const uint8_t> data_;
  uint64_t pos_, end_;
  std::string what_;
};

}  // namespace pms
