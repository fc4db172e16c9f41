// LeafSamples: every set holds distinct leaves of its own subtree, all of them while they fit, and
// both sides of every merge; garbage collection and renumbering keep the sets.
#include <gtest/gtest.h>
#include <algorithm>
#include <random>
#include <set>

#include "builder/leaf_samples.h"

namespace pms {
namespace {

// Mirrors the sets with plain leaf lists, merging random pairs the way collapses do.
struct Forest {
  explicit Forest(uint32_t n) : samples(n), leaves(n) {
    for (uint32_t v = 0; v < n; ++v) leaves[v] = {v};
  }
  void merge(uint32_t t, uint32_t u) {
    samples.merge(t, u);
    leaves[u].insert(leaves[t].begin(), leaves[t].end());
    leaves[t].clear();
  }
  void expect_consistent(uint32_t v) const {
    const auto set = samples.of(v);
    const std::set<uint32_t>& below = leaves[v];
    ASSERT_EQ(samples.leaf_count(v), below.size());
    EXPECT_EQ(set.size(), std::min<size_t>(below.size(), LeafSamples::kMax)) << "vertex " << v;
    EXPECT_EQ(std::set<uint32_t>(set.begin(), set.end()).size(), set.size()) << "a leaf sampled twice";
    for (uint32_t leaf : set) EXPECT_TRUE(below.count(leaf)) << "leaf " << leaf << " is not below vertex " << v;
  }
  LeafSamples samples;
  std::vector<std::set<uint32_t>> leaves;
};

TEST(LeafSamples, SetsHoldTheirOwnLeavesThroughMergesAndGarbageCollection) {
  constexpr uint32_t n = 20000;
  Forest forest(n);
  std::vector<uint32_t> alive(n);
  for (uint32_t v = 0; v < n; ++v) alive[v] = v;
  std::mt19937 random(7);
  while (alive.size() > 3) {  // many merges: the arena is collected many times over
    std::shuffle(alive.begin(), alive.end(), random);
    const uint32_t t = alive.back(), u = alive[alive.size() - 2];
    alive.pop_back();
    forest.merge(t, u);
    if (alive.size() % 997 == 0)
      for (uint32_t v : alive) forest.expect_consistent(v);
  }
  for (uint32_t v : alive) forest.expect_consistent(v);
}

TEST(LeafSamples, AMergeOverTheLimitKeepsBothSides) {
  constexpr uint32_t n = 4 * LeafSamples::kMax;
  Forest forest(n);
  // Two chains of 3 kMax and kMax leaves, then one merge of the two.
  for (uint32_t v = 1; v < 3 * LeafSamples::kMax; ++v) forest.merge(v, 0);
  for (uint32_t v = 3 * LeafSamples::kMax + 1; v < n; ++v) forest.merge(v, 3 * LeafSamples::kMax);
  forest.merge(3 * LeafSamples::kMax, 0);
  forest.expect_consistent(0);
  const auto set = forest.samples.of(0);
  const size_t from_small =
      size_t(std::count_if(set.begin(), set.end(), [](uint32_t leaf) { return leaf >= 3 * LeafSamples::kMax; }));
  EXPECT_EQ(from_small, LeafSamples::kMax / 4) << "the smaller subtree gets its share of the samples";
}

TEST(LeafSamples, CompactRenumbersTheLiveVertices) {
  constexpr uint32_t n = 1000;
  Forest forest(n);
  for (uint32_t v = 0; v < n; v += 2) forest.merge(v, v + 1);  // odd vertices survive
  std::vector<uint32_t> new_index(n, UINT32_MAX);
  for (uint32_t v = 1; v < n; v += 2) new_index[v] = v / 2;
  forest.samples.compact(new_index);
  for (uint32_t v = 1; v < n; v += 2) {
    const auto set = forest.samples.of(v / 2);
    EXPECT_EQ(std::set<uint32_t>(set.begin(), set.end()), (std::set<uint32_t>{v - 1, v}));
    EXPECT_EQ(forest.samples.leaf_count(v / 2), 2u);
  }
}

}  // namespace
}  // namespace pms
