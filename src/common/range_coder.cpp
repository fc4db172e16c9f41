// The range coder (common/range_coder.h). The encoder's low end is 33 bits wide: a carry out of the 32
// bits already decided is added to the byte held back in `cache_` (and the 0xFF bytes behind it) before
// any of them is written, so the output never has to be patched.
#include "common/range_coder.h"

#include <bit>
#include <cmath>

#include "common/error.h"

namespace pms {
namespace {

constexpr uint32_t kTop = uint32_t(1) << 24;  // as the decoder's

}  // namespace

void RangeEncoder::shift_low() {
  if (uint32_t(low_) < 0xFF000000u || (low_ >> 32) != 0) {
    const uint8_t carry = uint8_t(low_ >> 32);
    uint8_t held = cache_;
    do {
      out_.push_back(uint8_t(held + carry));
      held = 0xFF;
    } while (--cache_size_ != 0);
    cache_ = uint8_t(low_ >> 24);
  }
  ++cache_size_;
  low_ = (low_ & 0x00FFFFFFu) << 8;
}

void RangeEncoder::bit(AdaptiveBit& model, unsigned bit) {
  const uint32_t bound = (range_ >> AdaptiveBit::kBits) * model.zero;
  if (bit) {
    low_ += bound;
    range_ -= bound;
  } else {
    range_ = bound;
  }
  model.update(bit);
  while (range_ < kTop) {
    range_ <<= 8;
    shift_low();
  }
}

void RangeEncoder::raw(uint32_t value, unsigned n) {
  while (n > 0) {
    const unsigned k = n < kRawChunk ? n : kRawChunk;
    n -= k;
    range_ >>= k;
    low_ += uint64_t((value >> n) & ((uint32_t(1) << k) - 1)) * range_;
    while (range_ < kTop) {
      range_ <<= 8;
      shift_low();
    }
  }
}

void RangeEncoder::integer(AdaptiveInteger& model, uint32_t x) {
  const unsigned n = unsigned(std::bit_width(x));
  symbol(model.length, n);
  if (n < 2) return;
  bit(model.second[n], (x >> (n - 2)) & 1);
  raw(x, n - 2);
}

double RangeEncoder::bits() const { return 8.0 * double(out_.size() + cache_size_) + 32.0 - std::log2(double(range_)); }

std::vector<uint8_t> RangeEncoder::finish() {
  for (int i = 0; i < 5; ++i) shift_low();
  return std::move(out_);
}

RangeDecoder::RangeDecoder(std::span<const uint8_t> data, const std::string& where) : data_(data), where_(where) {
  for (int i = 0; i < 5; ++i) code_ = code_ << 8 | next_byte();
}

uint8_t RangeDecoder::next_byte() {
  if (at_ >= data_.size()) fail(where_, "truncated");
  return data_[at_++];
}

void RangeDecoder::normalize() {
  while (range_ < kTop) {
    range_ <<= 8;
    code_ = code_ << 8 | next_byte();
  }
}

uint32_t RangeDecoder::raw(unsigned n) {
  uint32_t value = 0;
  while (n > 0) {
    const unsigned k = n < kRawChunk ? n : kRawChunk;
    n -= k;
    range_ >>= k;
    const uint32_t chunk = code_ / range_;
    if (chunk >> k) fail(where_, "corrupt");  // an encoder never leaves the code above the range
    code_ -= chunk * range_;
    value = uint32_t((uint64_t(value) << k) | chunk);
    normalize();
  }
  return value;
}

uint32_t RangeDecoder::integer(AdaptiveInteger& model) {
  const uint32_t n = symbol(model.length);
  if (n > 32) fail(where_, "an integer of " + std::to_string(n) + " bits");
  if (n < 2) return n;
  const uint32_t second = bit(model.second[n]);
  const uint32_t low = raw(n - 2);
  return uint32_t((uint64_t(1) << (n - 1)) | (uint64_t(second) << (n - 2)) | low);
}

void RangeDecoder::expect_end() const {
  const size_t left = data_.size() - at_;
  if (left != 0) fail(where_, std::to_string(left) + (left == 1 ? " byte" : " bytes") + " after the stream's end");
}

}  // namespace pms
