// Canonical prefix codes: round trips, optimal-length sanity, the length limit, serialization, and
// hostile tables and streams rejected with pms::Error.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <optional>
#include <random>
#include <vector>

#include "common/bit_stream.h"
#include "common/error.h"
#include "common/prefix_code.h"

namespace pms {
namespace {

TEST(BitStream, FieldsAreLsbFirstAndReadsAreBounded) {
  BitWriter w;
  w.bits(0x5, 3);
  w.bits(0xABCD, 16);
  w.bit(1);
  ASSERT_EQ(w.size(), 20u);
  ASSERT_EQ(w.bytes().size(), 3u);
  EXPECT_EQ(w.bytes()[0], uint8_t(0x5 | (0xABCD << 3)));
  BitReader r(w.bytes(), 0, w.size(), "test");
  EXPECT_EQ(r.bits(3, "a"), 0x5u);
  EXPECT_EQ(r.bits(16, "b"), 0xABCDu);
  EXPECT_EQ(r.bit("c"), 1u);
  EXPECT_THROW(r.bit("d"), Error);  // the range ends at bit 20, inside the last byte
  EXPECT_THROW(BitReader(w.bytes(), 0, 25, "test"), Error);
}

TEST(PrefixCode, RoundTripsAndCostsNearTheEntropy) {
  std::mt19937_64 rng(7);
  std::geometric_distribution<uint32_t> geometric(0.3);
  std::vector<uint32_t> symbols(20000);
  std::vector<uint64_t> counts(40, 0);
  for (uint32_t& s : symbols) {
    s = std::min<uint32_t>(geometric(rng), 39);
    ++counts[s];
  }
  const PrefixCode code = PrefixCode::from_counts(counts);
  BitWriter w;
  double entropy = 0;
  for (uint64_t c : counts)
    if (c) entropy -= double(c) * std::log2(double(c) / double(symbols.size()));
  for (uint32_t s : symbols) code.write(w, s);
  EXPECT_LE(double(w.size()), entropy + double(symbols.size()));  // Huffman: within 1 bit a symbol
  EXPECT_GE(double(w.size()), entropy);
  BitReader r(w.bytes(), 0, w.size(), "test");
  for (uint32_t s : symbols) ASSERT_EQ(code.read(r, "symbol"), s);
  EXPECT_EQ(r.bits_left(), 0u);
}

TEST(PrefixCode, LengthsStayWithinTheLimit) {
  std::vector<uint64_t> fibonacci = {1, 1};
  while (fibonacci.size() < 40) fibonacci.push_back(fibonacci[fibonacci.size() - 1] + fibonacci[fibonacci.size() - 2]);
  const PrefixCode code = PrefixCode::from_counts(fibonacci);  // unlimited Huffman would need 39 bits
  for (uint8_t l : code.lengths()) {
    EXPECT_GE(l, 1u);
    EXPECT_LE(l, kMaxCodeLength);
  }
  BitWriter w;
  for (uint32_t s = 0; s < 40; ++s) code.write(w, s);
  BitReader r(w.bytes(), 0, w.size(), "test");
  for (uint32_t s = 0; s < 40; ++s) EXPECT_EQ(code.read(r, "symbol"), s);
}

TEST(PrefixCode, OneSymbolCostsNothingAndAbsentSymbolsAreRefused) {
  const std::vector<uint64_t> counts = {0, 0, 9, 0};
  const PrefixCode code = PrefixCode::from_counts(counts);
  BitWriter w;
  code.write(w, 2);
  EXPECT_EQ(w.size(), 0u);
  EXPECT_EQ(code.cost(2), 0u);
  BitReader r(w.bytes(), "test");
  EXPECT_EQ(code.read(r, "symbol"), 2u);
  EXPECT_THROW(code.write(w, 1), Error);
  EXPECT_THROW(code.write(w, 9), Error);
  const PrefixCode empty = PrefixCode::from_counts(std::vector<uint64_t>(3, 0));
  BitReader r2(w.bytes(), "test");
  EXPECT_THROW(empty.read(r2, "symbol"), Error);
}

TEST(PrefixCode, SerializesAndRejectsHostileTables) {
  const std::vector<uint64_t> counts = {5, 0, 3, 8, 1, 0, 0};
  const PrefixCode code = PrefixCode::from_counts(counts);
  BitWriter w;
  code.serialize(w);
  EXPECT_EQ(w.size(), 16u + 4 * 5);  // the two trailing absent symbols are dropped
  BitReader r(w.bytes(), 0, w.size(), "test");
  const PrefixCode back = PrefixCode::deserialize(r, counts.size(), "table");
  EXPECT_EQ(back.lengths(), code.lengths());
  BitReader small(w.bytes(), 0, w.size(), "test");
  EXPECT_THROW(PrefixCode::deserialize(small, 4, "table"), Error);  // 5 lengths for an alphabet of 4
  // Three code words of length 1 oversubscribe the code space.
  BitWriter bad;
  bad.bits(3, 16);
  for (int i = 0; i < 3; ++i) bad.bits(1, 4);
  BitReader rb(bad.bytes(), 0, bad.size(), "test");
  EXPECT_THROW(PrefixCode::deserialize(rb, 8, "table"), Error);
  BitReader truncated(w.bytes(), 0, 20, "test");
  EXPECT_THROW(PrefixCode::deserialize(truncated, counts.size(), "table"), Error);
  EXPECT_THROW(PrefixCode(std::vector<uint8_t>{16, 1}), Error);
}

TEST(PrefixCode, CodeSetsRoundTripAndRejectHostileSets) {
  std::mt19937_64 rng(7);
  std::vector<PrefixCode> codes;
  std::vector<size_t> alphabets;
  for (int i = 0; i < 60; ++i) {
    std::vector<uint64_t> counts(1 + rng() % 300, 0);
    const int used = i % 7 == 0 ? 0 : int(1 + rng() % 40);  // some codes empty, some with one symbol
    for (int k = 0; k < used; ++k) counts[rng() % counts.size()] += 1 + rng() % 1000;
    codes.push_back(PrefixCode::from_counts(counts));
    alphabets.push_back(counts.size());
  }
  std::vector<const PrefixCode*> pointers;
  for (const PrefixCode& c : codes) pointers.push_back(&c);
  BitWriter w;
  serialize_code_set(pointers, w);
  size_t plain = 0;
  for (const PrefixCode& c : codes) plain += 16 + 4 * c.serialized_symbols();
  EXPECT_LT(w.size(), plain);  // smaller than each code on its own
  BitReader r(w.bytes(), 0, w.size(), "set");
  const std::vector<PrefixCode> back = deserialize_code_set(r, alphabets, "set");
  ASSERT_EQ(back.size(), codes.size());
  for (size_t i = 0; i < codes.size(); ++i) EXPECT_EQ(back[i].lengths(), codes[i].lengths()) << i;
  EXPECT_EQ(r.bits_left(), 0u);
  for (uint64_t end = 0; end < w.size(); end += 1 + end / 16) {
    BitReader truncated(w.bytes(), 0, end, "set");
    EXPECT_THROW(deserialize_code_set(truncated, alphabets, "set"), Error) << end;
  }
  std::vector<size_t> smaller = alphabets;
  for (size_t& a : smaller) a = std::max<size_t>(1, a / 2);
  BitReader too_many(w.bytes(), 0, w.size(), "set");
  EXPECT_THROW(deserialize_code_set(too_many, smaller, "set"), Error);
  // A symbol count of 65536 or more; a step to a length below 1; a run of no code words past the count.
  std::vector<uint8_t> step_lengths(34, 0);
  step_lengths[14] = step_lengths[32] = 1;  // step -1 (code word 0) and a run of 3-10 (code word 1)
  const PrefixCode steps(step_lengths);
  for (const int hostile : {0, 1, 2}) {
    BitWriter bad;
    steps.serialize(bad);
    if (hostile == 0) {
      bad.bits(uint64_t(1) << 17, 18);  // 17 zero bits, then a one
    } else {
      bad.bits(0b010, 3);                 // m + 1 = 2 (a zero, a one, then 0): one length follows
      bad.bits(hostile == 1 ? 0 : 1, 1);  // step -1 from 0, or a run of at least 3
    }
    bad.bits(0, 32);
    BitReader rb(bad.bytes(), 0, bad.size(), "set");
    EXPECT_THROW(deserialize_code_set(rb, std::vector<size_t>{100}, "set"), Error) << hostile;
  }
}

TEST(PrefixCode, UnusedCodeWordsOfAnIncompleteCodeAreRejected) {
  const PrefixCode code(std::vector<uint8_t>{1, 2});  // 0, 10; 11 is unused
  BitWriter w;
  w.bits(0b11, 2);
  for (int i = 0; i < 16; ++i) w.bit(1);
  BitReader r(w.bytes(), 0, w.size(), "test");
  EXPECT_THROW(code.read(r, "symbol"), Error);
}

TEST(PrefixCode, RandomStreamsDecodeOrFailCleanly) {
  std::mt19937_64 rng(11);
  const PrefixCode code = PrefixCode::from_counts(std::vector<uint64_t>{1, 2, 3, 5, 8, 13, 0, 21});
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<uint8_t> bytes(rng() % 8);
    for (uint8_t& b : bytes) b = uint8_t(rng());
    BitReader r(bytes, "random");
    try {
      while (true) EXPECT_TRUE(code.has(code.read(r, "symbol")));
    } catch (const Error&) {
    }
  }
}

// The canonical code (two symbols or more) read one bit at a time, straight from the lengths: what read()'s
// table must agree with.
std::optional<uint32_t> read_by_bits(const std::vector<uint8_t>& lengths, BitReader& r) {
  uint32_t code = 0, first = 0;
  for (unsigned l = 1; l <= kMaxCodeLength; ++l) {
    if (r.bits_left() == 0) return std::nullopt;
    code |= r.bit("symbol");
    std::vector<uint32_t> of_length;
    for (uint32_t s = 0; s < lengths.size(); ++s)
      if (lengths[s] == l) of_length.push_back(s);
    if (code - first < of_length.size()) return of_length[code - first];
    first = uint32_t(first + of_length.size()) << 1;
    code <<= 1;
  }
  return std::nullopt;
}

TEST(PrefixCode, TableDecodingAgreesWithBitByBitDecoding) {
  std::mt19937_64 rng(5);
  for (int trial = 0; trial < 300; ++trial) {
    // Skewed counts give code words from 1 to kMaxCodeLength bits; some symbols absent.
    std::vector<uint64_t> counts(1 + rng() % 200);
    for (uint64_t& c : counts) c = rng() % 4 == 0 ? 0 : uint64_t(1) << (rng() % 24);
    const PrefixCode code = PrefixCode::from_counts(counts);
    if (std::count_if(counts.begin(), counts.end(), [](uint64_t c) { return c != 0; }) < 2) continue;  // reads no bits
    std::vector<uint8_t> bytes(rng() % 40);
    for (uint8_t& b : bytes) b = uint8_t(rng());
    const uint64_t end = bytes.empty() ? 0 : rng() % (8 * bytes.size() + 1);  // windows that end mid-data
    BitReader fast(bytes, 0, end, "fast"), slow(bytes, 0, end, "slow");
    for (;;) {
      std::optional<uint32_t> expected;
      try {
        expected = read_by_bits(code.lengths(), slow);
      } catch (const Error&) {
      }
      if (!expected) {
        EXPECT_THROW(code.read(fast, "symbol"), Error);
        break;
      }
      ASSERT_EQ(code.read(fast, "symbol"), *expected);
      ASSERT_EQ(fast.position(), slow.position());
    }
  }
}

}  // namespace
}  // namespace pms
