// <tree-id, node-id> (docs/internals.md, "Vertex ids"): derived from the packed arrays, children by shifting,
// find() as the inverse of id(), and the id widths reported by build/info.
#include <gtest/gtest.h>

#include "common/error.h"
#include "pm_fixtures.h"
#include "spm/hierarchy.h"
#include "spm/vertex_id.h"

namespace pms {
namespace {

TEST(HierarchyIds, SmallHierarchyIdsByShifting) {
  const Hierarchy h = test::make_small_hierarchy();
  const VertexId expected[9] = {{0, 1}, {1, 1}, {2, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {0, 6}, {0, 7}};
  for (uint32_t n = 0; n < h.node_count(); ++n) EXPECT_EQ(h.id(n), expected[n]) << "node " << n;
  for (uint32_t n = 0; n < h.node_count(); ++n) {
    if (h.is_leaf(n)) continue;
    EXPECT_EQ(h.id(h.first_child[n]).node, 2 * h.id(n).node);
    EXPECT_EQ(h.id(h.first_child[n] + 1).node, 2 * h.id(n).node + 1);
    EXPECT_EQ(h.id(h.first_child[n]).parent(), h.id(n));
  }
  EXPECT_EQ(h.leaf_count(), 6u);
  EXPECT_EQ(max_depth(h), 2u);
}

void expect_find_round_trip(const Hierarchy& h) {
  const ModelData v = model_of(h);
  for (uint32_t n = 0; n < h.node_count(); ++n) {
    ASSERT_EQ(h.find(h.id(n)), n);
    ASSERT_EQ(v.find(v.id(n)), n);
  }
}

TEST(HierarchyIds, FindIsTheInverseOfId) {
  expect_find_round_trip(test::make_small_hierarchy());
  Hierarchy forest = test::make_forest(5, [](uint32_t tree, int depth, bool) { return depth < int(tree) + 3; });
  forest.compute_ids();
  expect_find_round_trip(forest);
}

TEST(HierarchyIds, FindRejectsAbsentIds) {
  const Hierarchy h = test::make_small_hierarchy();
  const ModelData v = model_of(h);
  const VertexId absent[] = {
      {3, 1},                  // no such tree
      {UINT32_MAX, 1},         // nor this one
      {0, 0},                  // node-id without the leading 1
      {2, 2},                  // child of a leaf root
      {0, 4},                  // child of leaf 3
      {0, 14},                 // grandchild of leaf 7
      {0, uint64_t(1) << 63},  // deepest possible id, far below the tree
  };
  for (const VertexId id : absent) {
    EXPECT_EQ(h.find(id), kNone) << id.tree << "/" << id.node;
    EXPECT_EQ(v.find(id), kNone) << id.tree << "/" << id.node;
  }
  EXPECT_EQ(ModelData{}.find({0, 1}), kNone) << "an empty view has no roots";
}

TEST(HierarchyIds, FindNeverReadsPastTruncatedArrays) {
  Hierarchy h = test::make_small_hierarchy();
  h.root_count = 5;         // claims more roots than there are nodes of this size
  h.first_child.resize(4);  // and node 0's children (3, 4) run past the end
  EXPECT_EQ(h.find({4, 1}), kNone);
  EXPECT_EQ(h.find({0, 3}), kNone);
  EXPECT_EQ(h.find({0, 1}), 0u);
}

TEST(HierarchyIds, DepthSixtyThreeFitsAndSixtyFourThrows) {
  const auto chain = [](int levels) {
    return [levels](uint32_t tree, int depth, bool leftmost) { return tree == 0 && leftmost && depth < levels; };
  };
  Hierarchy deep = test::make_forest(2, chain(63));
  deep.compute_ids();
  EXPECT_EQ(max_depth(deep), 63u);
  const uint32_t last = uint32_t(deep.node_count() - 1);
  EXPECT_EQ(deep.id(last).depth(), 63);
  EXPECT_EQ(deep.id(last).node >> 63, 1u);
  EXPECT_EQ(deep.find(deep.id(last)), last);

  Hierarchy too_deep = test::make_forest(2, chain(64));
  EXPECT_EQ(max_depth(too_deep), 64u);
  try {
    too_deep.compute_ids();
    FAIL() << "depth 64 does not fit a 64-bit node-id";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("deeper than 63 levels"), std::string::npos) << e.what();
  }
}

TEST(HierarchyIds, TreeIdBits) {
  // kim-lee-kobbelt Table 1: base vertex counts and their tree-id bits.
  EXPECT_EQ(tree_id_bits(62), 6u);
  EXPECT_EQ(tree_id_bits(75), 7u);
  EXPECT_EQ(tree_id_bits(12), 4u);
  EXPECT_EQ(tree_id_bits(146), 8u);
  EXPECT_EQ(tree_id_bits(65), 7u);
  // Edges: powers of two need exactly log2 bits; one or zero trees still get a 1-bit field.
  EXPECT_EQ(tree_id_bits(64), 6u);
  EXPECT_EQ(tree_id_bits(2), 1u);
  EXPECT_EQ(tree_id_bits(1), 1u);
  EXPECT_EQ(tree_id_bits(0), 1u);
  EXPECT_EQ(tree_id_bits(uint64_t(1) << 32), 32u);
  EXPECT_EQ(tree_id_bits((uint64_t(1) << 32) + 1), 33u);
}

TEST(HierarchyIds, ViewOfAliasesTheVectors) {
  const Hierarchy h = test::make_small_hierarchy();
  const ModelData v = model_of(h);
  EXPECT_EQ(v.root_count, h.root_count);
  EXPECT_EQ(v.node_count(), h.node_count());
  EXPECT_EQ(v.parent.data(), h.parent.data());
  EXPECT_EQ(v.position.data(), h.position.data());
  EXPECT_EQ(v.position.size(), h.position.size());
  EXPECT_EQ(v.refine.data(), h.refine.data());
  EXPECT_EQ(v.normals.size(), h.normals.size());
  EXPECT_EQ(v.colors.size(), h.colors.size());
  EXPECT_EQ(v.node_id.data(), h.node_id.data());
  EXPECT_EQ(v.bbox_min, h.bbox_min);
  EXPECT_EQ(v.scale, h.scale);
  for (uint32_t n = 0; n < h.node_count(); ++n) {
    EXPECT_EQ(v.is_leaf(n), h.is_leaf(n));
    EXPECT_EQ(v.id(n), h.id(n));
  }
}

}  // namespace
}  // namespace pms
