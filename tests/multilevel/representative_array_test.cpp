// RepresentativeArray (multilevel/representative_array.h): 3 bytes per entry while every index and the "none"
// mark fit in 24 bits, 4 beyond; either width reads back what was written, through both accessors.
#include <gtest/gtest.h>

#include <utility>
#include <vector>

#include "multilevel/representative_array.h"

namespace pms {
namespace {

constexpr uint32_t kNone = RepresentativeArray::kNone;

// The largest index a vertex count allows, its neighbours and "none", written and read back both ways.
void expect_round_trip(size_t n, unsigned width) {
  RepresentativeArray a;
  a.assign(n, kNone);
  ASSERT_EQ(a.width(), width);
  EXPECT_EQ(a.bytes(), width * n);
  const uint32_t last = uint32_t(n - 1);
  a[last] = last - 1;
  a[last - 1] = kNone;
  a[0] = last;  // not a valid representative, but the array holds any index below n
  EXPECT_EQ(a[last], last - 1);
  EXPECT_EQ(std::as_const(a)[last - 1], kNone);
  EXPECT_EQ(std::as_const(a)[0], last);
  EXPECT_EQ(std::as_const(a)[1], kNone);
  a.visit([&](auto reader) {
    EXPECT_EQ(reader[last], last - 1);
    EXPECT_EQ(reader[last - 1], kNone);
    EXPECT_EQ(reader[0], last);
  });
}

TEST(RepresentativeArray, NarrowWhileIndicesAndNoneFitIn24Bits) { expect_round_trip(0xFFFFFE, 3); }

TEST(RepresentativeArray, WideFromTheCountWhereAnIndexWouldMeetNone) { expect_round_trip(0xFFFFFF, 4); }

TEST(RepresentativeArray, BuiltFromValuesComparesByValue) {
  const RepresentativeArray a = {kNone, 0, 1, kNone, 2};
  EXPECT_EQ(a.size(), 5u);
  EXPECT_EQ(a, (std::vector<uint32_t>{kNone, 0, 1, kNone, 2}));
  EXPECT_EQ(a.values(), (std::vector<uint32_t>{kNone, 0, 1, kNone, 2}));
  RepresentativeArray b(a.values());
  EXPECT_EQ(a, b);
  b[4] = 1;
  EXPECT_FALSE(a == b);
  EXPECT_TRUE(RepresentativeArray().empty());
}

}  // namespace
}  // namespace pms
