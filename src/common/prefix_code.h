// Static canonical prefix codes (Huffman 1952; canonical form as in DEFLATE, RFC 1951 §3.2.2): the entropy
// coder of the split records (spm/split_codec.h). A static code costs no termination bits per record, which
// an arithmetic or rANS coder would pay on every ~30-bit record that must decode on its own.
#pragma once
#include <cstdint>
#include <span>
#include <vector>

#include "common/bit_stream.h"

namespace pms {

constexpr unsigned kMaxCodeLength = 15;

class PrefixCode {
 public:
  PrefixCode() = default;
  // Lengths per symbol (0 = the symbol never occurs). Throws pms::Error for a length above
  // kMaxCodeLength or lengths that oversubscribe the code space (Kraft sum > 1); an incomplete code is
  // allowed, and its unused code words are rejected when read. A code with a single symbol costs 0 bits.
  explicit PrefixCode(std::vector<uint8_t> lengths);
  // Huffman lengths for `counts`, limited to kMaxCodeLength. Symbols counted 0 get no code word.
  static PrefixCode from_counts(std::span<const uint64_t> counts);

  size_t alphabet() const { return lengths_.size(); }
  bool has(uint32_t symbol) const { return symbol < lengths_.size() && lengths_[symbol] != 0; }
  // Bits the symbol costs (0 for the only symbol of a one-symbol code); the symbol must be present.
  unsigned cost(uint32_t symbol) const { return single_ ? 0 : lengths_[symbol]; }
  const std::vector<uint8_t>& lengths() const { return lengths_; }
  // The code word write() puts, in stream order from the lowest bit; the symbol must be present.
  uint32_t word(uint32_t symbol) const { return single_ ? 0 : codes_[symbol]; }

  // Throws pms::Error when the symbol has no code word.
  void write(BitWriter& w, uint32_t symbol) const;
  uint32_t read(BitReader& r, const char* field) const;

  // Serialized form: u16 symbols-with-lengths count m (the alphabet's trailing absent symbols dropped),
  // then m lengths of 4 bits. `deserialize` accepts m <= alphabet and fills the rest with 0.
  void serialize(BitWriter& w) const;
  static PrefixCode deserialize(BitReader& r, size_t alphabet, const char* field);
  // The symbols-with-lengths count m as above.
  size_t serialized_symbols() const;

 private:
  std::vector<uint8_t> lengths_;
  std::vector<uint16_t> codes_;   // per symbol, canonical, bit-reversed: in stream order from the lowest bit
  std::vector<uint16_t> count_;   // code words per length, 0..kMaxCodeLength
  std::vector<uint32_t> sorted_;  // symbols in canonical order (by length, then symbol)
  // Per kFastBits-bit window of the stream (first bit lowest): length << 12 | symbol of the code word it
  // starts with, 0 when that word is longer or unused; read() falls back to one bit at a time then.
  static constexpr unsigned kFastBits = 8;
  std::vector<uint16_t> fast_;
  bool single_ = false;
};

// Many codes serialized together, for a coder with hundreds of mostly small tables. First the *length
// code*, fitted to the whole set, in the form above: 34 symbols, 0..30 the step from the previous nonzero
// length of the code (from 0 for its first) to the next, minus 15; 31 one symbol without a code word; 32
// and 33 runs of 3-10 and 11-138 of them, with 3 and 7 raw bits (DEFLATE's code-length codes, RFC 1951
// §3.2.7). Then per code m + 1 as an Elias gamma code (bit_width(m + 1) - 1 zero bits, a one, then the
// bits below the leading one) and its m lengths in the length code. `deserialize_code_set` takes each
// code's alphabet and rejects what `deserialize` does, steps to a length outside 1..15 and runs past m.
void serialize_code_set(std::span<const PrefixCode* const> codes, BitWriter& w);
std::vector<PrefixCode> deserialize_code_set(BitReader& r, std::span<const size_t> alphabets, const char* field);

}  // namespace pms
