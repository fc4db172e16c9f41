// common/parallel.h: map_ranges covers [0, count) once, in range order, and reports errors as a
// sequential loop would (the first failing item's), however many ranges ran; map_bounded_ranges runs
// the ranges it is given.
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "common/parallel.h"

namespace pms {
namespace {

TEST(Parallel, MapRangesCoversEveryItemOnceInOrder) {
  for (size_t count : {size_t(0), size_t(1), size_t(7), size_t(100000)}) {
    const auto ranges = map_ranges(count, 16, [](size_t begin, size_t end) { return std::pair{begin, end}; });
    ASSERT_FALSE(ranges.empty());
    size_t next = 0;
    for (const auto& [begin, end] : ranges) {
      EXPECT_EQ(begin, next);
      EXPECT_LE(begin, end);
      next = end;
    }
    EXPECT_EQ(next, count);
    if (count < 16) {
      EXPECT_EQ(ranges.size(), 1u);  // below min_parallel: inline
    }
  }
}

TEST(Parallel, MapRangesRethrowsTheErrorASequentialLoopMeetsFirst) {
  constexpr size_t kCount = 100000;
  const std::vector<size_t> bad = {kCount / 2, kCount - 1, kCount / 2 + 3};
  try {
    map_ranges(kCount, 16, [&](size_t begin, size_t end) {
      for (size_t i = begin; i < end; ++i)
        for (size_t b : bad)
          if (i == b) throw std::runtime_error("item " + std::to_string(i));
      return end - begin;
    });
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), "item " + std::to_string(kCount / 2));
  }
}

TEST(Parallel, BoundedRangesRunTheGivenRangesInOrderEvenWhenUneven) {
  const std::vector<size_t> bounds = {0, 90, 90, 95, 100};  // as split_codec's ranges of equal split counts
  const auto ranges = map_bounded_ranges(bounds, [](size_t begin, size_t end) { return std::pair{begin, end}; });
  ASSERT_EQ(ranges.size(), 4u);
  for (size_t i = 0; i < ranges.size(); ++i) EXPECT_EQ(ranges[i], std::pair(bounds[i], bounds[i + 1]));
  try {
    map_bounded_ranges(bounds, [](size_t begin, size_t end) {
      if (end == 100 || end == 95) throw std::runtime_error("range ending at " + std::to_string(end));
      return begin;
    });
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), "range ending at 95");
  }
  EXPECT_EQ(even_bounds(10, 3), (std::vector<size_t>{0, 3, 6, 10}));
}

}  // namespace
}  // namespace pms
