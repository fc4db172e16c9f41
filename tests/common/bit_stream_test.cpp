// common/bit_stream.h: fields of any width at any bit offset round-trip, LSB first, against a plain
// bit-at-a-time model of the format; reads stay inside their window.
#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "common/bit_stream.h"
#include "common/error.h"

namespace pms {
namespace {

uint64_t low_bits(uint64_t value, unsigned n) { return n == 64 ? value : value & ((uint64_t(1) << n) - 1); }

TEST(BitStream, FieldsOfEveryWidthRoundTripAtEveryOffset) {
  std::mt19937_64 rng(7);
  std::vector<std::pair<uint64_t, unsigned>> fields;
  std::vector<int> model;  // the stream, one bit per entry
  BitWriter w;
  for (int i = 0; i < 5000; ++i) {
    const unsigned n = unsigned(rng() % 65);
    const uint64_t value = rng();
    fields.push_back({low_bits(value, n), n});
    for (unsigned k = 0; k < n; ++k) model.push_back(int(value >> k) & 1);
    w.bits(value, n);  // bits above n are ignored
    if (i % 3 == 0) {  // single bits between the fields shift every later offset
      w.bit(unsigned(value >> 63));
      fields.push_back({value >> 63, 1});
      model.push_back(int(value >> 63));
    }
  }
  ASSERT_EQ(w.size(), model.size());
  ASSERT_EQ(w.bytes().size(), (model.size() + 7) / 8);
  for (size_t k = 0; k < model.size(); ++k) ASSERT_EQ((w.bytes()[k >> 3] >> (k & 7)) & 1, model[k]) << "bit " << k;
  for (size_t k = model.size(); k < 8 * w.bytes().size(); ++k) EXPECT_EQ((w.bytes()[k >> 3] >> (k & 7)) & 1, 0);

  BitReader r(w.bytes(), "stream");
  for (const auto& [value, n] : fields) ASSERT_EQ(r.bits(n, "field"), value);
  EXPECT_LT(r.bits_left(), 8u);

  BitWriter copy;
  copy.bits(5, 3);
  copy.append(w);
  BitReader again(copy.bytes(), 3, copy.size(), "copy");
  for (const auto& [value, n] : fields) ASSERT_EQ(again.bits(n, "field"), value);
  EXPECT_EQ(again.bits_left(), 0u);
}

// Servers copy stored records with append: any window of any data, at any offset of the writer, near the
// data's end too (where fewer than 8 bytes are left to load).
TEST(BitStream, AppendCopiesAnyWindowBitForBit) {
  std::mt19937_64 rng(11);
  std::vector<uint8_t> data(37);
  for (uint8_t& b : data) b = uint8_t(rng());
  for (int trial = 0; trial < 2000; ++trial) {
    const uint64_t end = rng() % (8 * data.size() + 1), begin = end ? rng() % (end + 1) : 0;
    const unsigned lead = unsigned(rng() % 20);
    BitWriter w;
    w.bits(rng(), lead);
    w.append(data, begin, end);
    ASSERT_EQ(w.size(), lead + end - begin);
    BitReader copied(w.bytes(), lead, w.size(), "copy");
    for (uint64_t k = begin; k < end; ++k)
      ASSERT_EQ(copied.bit("bit"), (data[k >> 3] >> (k & 7)) & 1u) << begin << " " << end;
    for (uint64_t k = w.size(); k < 8 * w.bytes().size(); ++k) ASSERT_EQ((w.bytes()[k >> 3] >> (k & 7)) & 1, 0);
  }
  BitWriter w;
  EXPECT_THROW(w.append(data, 0, 8 * data.size() + 1), Error);
  EXPECT_THROW(w.append(data, 9, 8), Error);
}

TEST(BitStream, ReadsStayInsideTheirWindow) {
  BitWriter w;
  w.bits(0xABCDEF, 24);
  BitReader r(w.bytes(), 4, 13, "window");
  EXPECT_EQ(r.bits(9, "field"), (0xABCDEFu >> 4) & 0x1FF);
  EXPECT_THROW(r.bit("past the end"), Error);
  BitReader s(w.bytes(), 0, 10, "window");
  EXPECT_THROW(s.bits(11, "field"), Error);
  EXPECT_THROW(BitReader(w.bytes(), 0, 25, "too long"), Error);
}

}  // namespace
}  // namespace pms
