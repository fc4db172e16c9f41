// The lattices of nested refinement info (spm/nested_info.h): the entry chosen for a value is the lowest
// one that holds it, entries fall with k, and entry 0 is the parent's own value.
#include <gtest/gtest.h>

#include <random>

#include "spm/nested_info.h"

namespace pms {
namespace {

TEST(NestedInfo, LengthEntriesAreTheLowestThatHold) {
  std::mt19937 rng(19);
  std::uniform_int_distribution<uint32_t> code(0, 0x7C0);
  for (const uint32_t step : {kRadiusCodesPerStep, kMuCodesPerStep, kDeltaCodesPerStep}) {
    for (int i = 0; i < 20000; ++i) {
      const auto parent = uint16_t(code(rng) << kLengthDroppedBits), own = uint16_t(code(rng) << kLengthDroppedBits);
      EXPECT_EQ(length_at_entry(parent, 0, step), parent);
      const uint32_t k = length_entry(parent, own, step);
      if (own > parent) {
        EXPECT_EQ(k, kNoEntry);
        continue;
      }
      if (k == kNoEntry) continue;  // far below the parent: exact
      const uint32_t at = length_at_entry(parent, k, step), next = length_at_entry(parent, k + 1, step);
      EXPECT_GE(at, own);
      EXPECT_LE(at, parent);
      EXPECT_TRUE(next == kNoEntry || next < own) << parent << " " << own << " " << step;
    }
  }
}

TEST(NestedInfo, AngleEntriesAreTheLowestThatHold) {
  for (uint32_t parent = 0; parent <= kConeSteps; parent += 7) {
    EXPECT_EQ(angle_at_entry(uint16_t(parent), 0), parent);
    uint32_t previous = parent;
    for (uint32_t k = 1; angle_at_entry(uint16_t(parent), k) != kNoEntry; ++k) {
      EXPECT_LE(angle_at_entry(uint16_t(parent), k), previous);
      previous = angle_at_entry(uint16_t(parent), k);
    }
    for (uint32_t own = 0; own <= parent; own += 5) {
      const uint32_t k = angle_entry(uint16_t(parent), uint16_t(own));
      if (k == kNoEntry) continue;
      EXPECT_GE(angle_at_entry(uint16_t(parent), k), own);
      const uint32_t next = angle_at_entry(uint16_t(parent), k + 1);
      EXPECT_TRUE(next == kNoEntry || next < own);
    }
    EXPECT_EQ(angle_entry(uint16_t(parent), uint16_t(parent + 1)), kNoEntry);
  }
}

}  // namespace
}  // namespace pms
