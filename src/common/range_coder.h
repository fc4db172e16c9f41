// An adaptive binary range coder (Martin 1979, "Range encoding"; the carry-less byte-wise form with a
// cached byte that LZMA uses): each binary decision is coded under a probability that follows what it
// has seen, so a stream of skewed, context-dependent decisions costs close to their entropy. Integers go
// through a tree of such decisions (their bit length) and then raw bits below the leading one, the same
// split as the prefix codes' (common/prefix_code.h), with the length's code learned on the way.
// The decoder throws pms::Error rather than read past its data, so hostile input costs bounded work.
#pragma once
#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace pms {

// The probability that the next decision is 0, in 1/2048ths, and how fast it follows what it sees.
struct AdaptiveBit {
  static constexpr unsigned kBits = 11, kShift = 5;
  uint16_t zero = 1u << (kBits - 1);
  void update(unsigned bit) {
    if (bit)
      zero = uint16_t(zero - (zero >> kShift));
    else
      zero = uint16_t(zero + (((1u << kBits) - zero) >> kShift));
  }
};

// A symbol of `Bits` bits as that many decisions, most significant first, each under the probability
// of the bits above it.
template <unsigned Bits>
struct AdaptiveSymbol {
  static constexpr uint32_t kSymbols = uint32_t(1) << Bits;
  std::array<AdaptiveBit, kSymbols> node{};
};

// An unsigned integer: its bit length (0 … 32) as an adaptive symbol, the bit below the leading one
// adaptive per length, the rest raw.
struct AdaptiveInteger {
  AdaptiveSymbol<6> length;
  std::array<AdaptiveBit, 33> second{};
};

// Raw bits the coders take in one step.
constexpr unsigned kRawChunk = 16;

class RangeEncoder {
 public:
  void bit(AdaptiveBit& model, unsigned bit);
  // n <= 32 bits, each at probability 1/2, most significant first, up to kRawChunk of them in one step
  // (the range, at least 2^24, divided by 2^kRawChunk still tells them apart).
  void raw(uint32_t value, unsigned n);
  template <unsigned Bits>
  void symbol(AdaptiveSymbol<Bits>& model, uint32_t s) {
    uint32_t node = 1;
    for (unsigned i = Bits; i-- > 0;) {
      const unsigned b = (s >> i) & 1;
      bit(model.node[node], b);
      node = node << 1 | b;
    }
  }
  void integer(AdaptiveInteger& model, uint32_t x);
  // Bits the stream holds so far, fractions included (what a part of it costs: the difference).
  double bits() const;
  // The stream, flushed; the encoder is spent.
  std::vector<uint8_t> finish();

 private:
  void shift_low();
  uint64_t low_ = 0;
  uint32_t range_ = 0xFFFFFFFFu;
  uint8_t cache_ = 0;
  uint64_t cache_size_ = 1;
  std::vector<uint8_t> out_;
};

class RangeDecoder {
 public:
  // `where` names the data in errors ("WHERE: truncated"); it must outlive the decoder.
  RangeDecoder(std::span<const uint8_t> data, const std::string& where);
  // Inline: a level's decoding is mostly this.
  unsigned bit(AdaptiveBit& model) {
    const uint32_t bound = (range_ >> AdaptiveBit::kBits) * model.zero;
    unsigned bit = 0;
    if (code_ < bound) {
      range_ = bound;
    } else {
      code_ -= bound;
      range_ -= bound;
      bit = 1;
    }
    model.update(bit);
    if (range_ < kTop) normalize();
    return bit;
  }
  uint32_t raw(unsigned n);
  template <unsigned Bits>
  uint32_t symbol(AdaptiveSymbol<Bits>& model) {
    uint32_t node = 1;
    for (unsigned i = 0; i < Bits; ++i) node = node << 1 | bit(model.node[node]);
    return node - AdaptiveSymbol<Bits>::kSymbols;
  }
  // pms::Error for a length above 32.
  uint32_t integer(AdaptiveInteger& model);
  // pms::Error unless every byte was read: what follows the stream is not part of it.
  void expect_end() const;

 private:
  static constexpr uint32_t kTop = uint32_t(1) << 24;  // below this the range takes one more byte
  uint8_t next_byte();
  void normalize();
  std::span<const uint8_t> data_;
  const std::string& where_;
  size_t at_ = 0;
  uint32_t range_ = 0xFFFFFFFFu, code_ = 0;
};

}  // namespace pms
