// The client's partial hierarchy (UpdateVHierarchy, kim-lee-kobbelt §5.3): slots, ids, inheritance of
// v_u's geometry, rejection of bad packets, and a round trip through split_record() on complete models.
#include <gtest/gtest.h>
#include <algorithm>

#include "common/error.h"
#include "reference_pm.h"
#include "spm/hierarchy.h"
#include "spm/refine_info.h"
#include "spm/split_record.h"
#include "spm/vertex_hierarchy.h"
#include "spm/vertex_id.h"

namespace pms {
namespace {

const float kOrigin[3] = {0, 0, 0};

RefineInfo info(uint16_t tag) { return RefineInfo{tag, 0, 0, 0, 0, kNoCone}; }

VertexHierarchy three_roots() {
  VertexHierarchy h;
  for (uint32_t r = 0; r < 3; ++r) {
    const float p[3] = {float(r), 0, 0};
    h.add_root({r, 1}, p, info(uint16_t(r)));
  }
  return h;
}

SplitRecord split_of(VertexId vs, VertexId cut_l, VertexId cut_r) {
  SplitRecord s;
  s.vs = vs;
  s.cut_l = cut_l;
  s.cut_r = cut_r;
  s.position_t[0] = 7;
  s.position_t[1] = 8;
  s.position_t[2] = 9;
  s.info_t = info(100);
  s.info_u = info(101);
  return s;
}

TEST(VertexHierarchy, SplitAttachesChildrenAsLeaves) {
  VertexHierarchy h = three_roots();
  EXPECT_EQ(h.root_count(), 3u);
  const uint32_t root0 = h.find({0, 1});
  ASSERT_NE(root0, kNone);
  EXPECT_TRUE(h.is_leaf(root0));

  const uint32_t t = h.add_split(split_of({0, 1}, {1, 1}, {2, 5}));
  const uint32_t u = t + 1;
  EXPECT_FALSE(h.is_leaf(root0));
  EXPECT_EQ(h.first_child(root0), t);
  EXPECT_EQ(h.id(t), (VertexId{0, 2}));
  EXPECT_EQ(h.id(u), (VertexId{0, 3}));
  EXPECT_EQ(h.find({0, 2}), t);
  EXPECT_EQ(h.find({0, 3}), u);
  EXPECT_EQ(h.parent(t), root0);
  EXPECT_EQ(h.parent(u), root0);
  EXPECT_TRUE(h.is_leaf(t) && h.is_leaf(u));
  EXPECT_EQ(h.cut_left(root0), (VertexId{1, 1}));
  EXPECT_EQ(h.cut_right(root0), (VertexId{2, 5}));
  // v_t gets the packet's position, v_u keeps v_s's (half-edge collapse t -> u).
  EXPECT_EQ(h.position(t)[0], 7);
  EXPECT_EQ(h.position(t)[2], 9);
  EXPECT_EQ(h.position(u)[0], 0);
  EXPECT_EQ(h.refine(t), info(100));
  EXPECT_EQ(h.refine(u), info(101));
  EXPECT_EQ(h.find({0, 4}), kNone);
  EXPECT_EQ(h.find({3, 1}), kNone);

  // One-sided (boundary) split of a child, then a grandchild.
  const uint32_t t2 = h.add_split(split_of({0, 3}, kNoVertex, {1, 1}));
  EXPECT_EQ(h.id(t2), (VertexId{0, 6}));
  EXPECT_FALSE(is_vertex(h.cut_left(u)));
  EXPECT_EQ(h.position(t2 + 1)[0], 0);  // v_u of <0,3> inherits <0,3>'s position, i.e. the root's
}

TEST(VertexHierarchy, RejectsBadPackets) {
  VertexHierarchy h = three_roots();
  EXPECT_THROW(h.add_split(split_of({0, 2}, {1, 1}, kNoVertex)), Error);     // unknown node
  EXPECT_THROW(h.add_split(split_of({0, 1}, kNoVertex, kNoVertex)), Error);  // no cut vertex
  EXPECT_THROW(h.add_split(split_of({0, 1}, {0, 5}, kNoVertex)), Error);     // cut inside v_s's subtree
  EXPECT_THROW(h.add_split(split_of({0, 1}, {9, 1}, kNoVertex)), Error);     // cut in an unknown tree
  EXPECT_EQ(h.size(), 3u);                                                   // nothing half-added
  h.add_split(split_of({0, 1}, {1, 1}, kNoVertex));
  EXPECT_THROW(h.add_split(split_of({0, 1}, {1, 1}, kNoVertex)), Error);  // split twice

  // Roots must be <root_count, 1>.
  EXPECT_THROW(h.add_root({5, 1}, kOrigin, info(0)), Error);
  EXPECT_THROW(h.add_root({3, 2}, kOrigin, info(0)), Error);

  // A node at depth 63 has no room for children in a 64-bit node id.
  VertexHierarchy deep;
  deep.add_root({0, 1}, kOrigin, info(0));
  deep.add_root({1, 1}, kOrigin, info(0));
  VertexId v{0, 1};
  for (int d = 0; d < 63; ++d) {
    deep.add_split(split_of(v, {1, 1}, kNoVertex));
    v = v.child(1);
  }
  EXPECT_EQ(v.depth(), 63);
  EXPECT_NE(deep.find(v), kNone);
  EXPECT_THROW(deep.add_split(split_of(v, {1, 1}, kNoVertex)), Error);
}

TEST(VertexHierarchy, AttributesAreRequiredAndInherited) {
  VertexHierarchy h(true, true);
  const float n0[3] = {0, 0, 1};
  const uint8_t c0[4] = {1, 2, 3, 4};
  EXPECT_THROW(h.add_root({0, 1}, kOrigin, info(0)), Error);
  h.add_root({0, 1}, kOrigin, info(0), n0, c0);
  h.add_root({1, 1}, kOrigin, info(0), n0, c0);
  SplitRecord s = split_of({0, 1}, {1, 1}, kNoVertex);
  EXPECT_THROW(h.add_split(s), Error);
  s.has_normal = s.has_color = true;
  s.normal_t[0] = 1;
  s.color_t[0] = 9;
  const uint32_t t = h.add_split(s);
  EXPECT_EQ(h.normal(t)[0], 1);
  EXPECT_EQ(h.color(t)[0], 9);
  EXPECT_EQ(h.normal(t + 1)[2], 1);  // v_u inherits v_s's attributes
  EXPECT_EQ(h.color(t + 1)[3], 4);
}

TEST(VertexHierarchy, FindsEveryNodeOfALargeForest) {
  VertexHierarchy h;
  const uint32_t roots = 20000;
  for (uint32_t r = 0; r < roots; ++r) h.add_root({r, 1}, kOrigin, info(0));
  // Split every root twice more (root, then its v_u), growing the table several times.
  for (uint32_t r = 0; r < roots; ++r) {
    h.add_split(split_of({r, 1}, {(r + 1) % roots, 1}, kNoVertex));
    h.add_split(split_of({r, 3}, {(r + 1) % roots, 1}, kNoVertex));
  }
  ASSERT_EQ(h.size(), 5 * roots);
  for (uint32_t slot = 0; slot < h.size(); ++slot) ASSERT_EQ(h.find(h.id(slot)), slot);
  EXPECT_EQ(h.find({roots, 1}), kNone);
  EXPECT_EQ(h.find({0, 4}), kNone);
  EXPECT_EQ(h.find({0, 7}), h.find({0, 6}) + 1);
}

TEST(VertexHierarchy, SplitRecordsRebuildTheModel) {
  const test::ReferenceModel model = test::build_reference_model(test::make_icosphere(2), 11);
  const ModelData view = model.model();
  VertexHierarchy h = VertexHierarchy::from_model(view);
  ASSERT_EQ(h.root_count(), view.root_count);
  EXPECT_EQ(h.size(), view.root_count);
  EXPECT_TRUE(h.has_normals() && h.has_colors());
  for (uint32_t node : view.split_order) h.add_split(split_record(view, node));
  ASSERT_EQ(h.size(), view.node_count());
  for (uint32_t node = 0; node < view.node_count(); ++node) {
    const uint32_t slot = h.find(view.id(node));
    ASSERT_NE(slot, kNone) << "node " << node;
    EXPECT_TRUE(std::equal(h.position(slot), h.position(slot) + 3, &view.position[3 * node])) << "node " << node;
    EXPECT_TRUE(std::equal(h.normal(slot), h.normal(slot) + 3, &view.normals[3 * node])) << "node " << node;
    EXPECT_TRUE(std::equal(h.color(slot), h.color(slot) + 4, &view.colors[4 * node])) << "node " << node;
    EXPECT_EQ(h.refine(slot), view.refine[node]);
    EXPECT_EQ(h.is_leaf(slot), view.is_leaf(node));
    if (view.is_leaf(node)) continue;
    EXPECT_EQ(h.id(h.first_child(slot)), view.id(view.first_child[node]));
    const uint32_t cl = view.cut_left[node], cr = view.cut_right[node];
    EXPECT_EQ(h.cut_left(slot), cl == kNone ? kNoVertex : view.id(cl));
    EXPECT_EQ(h.cut_right(slot), cr == kNone ? kNoVertex : view.id(cr));
  }
  EXPECT_THROW(split_record(view, model.leaf_node[0]), Error);
  EXPECT_THROW(split_record(view, uint32_t(view.node_count())), Error);
}

}  // namespace
}  // namespace pms
