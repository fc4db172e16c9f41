// Properties of built hierarchies (docs/internals.md, "The core model"): ids, breadth-first packing, cut vertices,
// conservative refinement info, split order — on generated meshes and on real scans.
#include <gtest/gtest.h>
#include <cmath>
#include <set>

#include "builder/build.h"
#include "io/manifold_check.h"
#include "io/shapes.h"
#include "spm/hierarchy.h"
#include "spm/refine_info.h"
#include "spm/vertex_id.h"
#include "test_support.h"

namespace pms {
namespace {

double distance(const float* a, const float* b) {
  return std::sqrt(double(a[0] - b[0]) * (a[0] - b[0]) + double(a[1] - b[1]) * (a[1] - b[1]) +
                   double(a[2] - b[2]) * (a[2] - b[2]));
}

// atan2 form: acos of a dot product near 1 loses ~sqrt(float epsilon) of precision.
double angle(const float* a, const float* b) {
  const double d = double(a[0]) * b[0] + double(a[1]) * b[1] + double(a[2]) * b[2];
  const double cx = double(a[1]) * b[2] - double(a[2]) * b[1], cy = double(a[2]) * b[0] - double(a[0]) * b[2],
               cz = double(a[0]) * b[1] - double(a[1]) * b[0];
  return std::atan2(std::sqrt(cx * cx + cy * cy + cz * cz), d);
}

void expect_valid_hierarchy(const Mesh& mesh, const BuildResult& built) {
  const Hierarchy& h = built.hierarchy;
  const size_t n = h.node_count();
  ASSERT_EQ(h.leaf_count(), mesh.vertex_count());
  ASSERT_EQ(n, 2 * mesh.vertex_count() - h.root_count);
  ASSERT_EQ(built.stats.vsplits, mesh.vertex_count() - h.root_count);

  std::set<std::pair<uint32_t, uint64_t>> ids;
  int previous_depth = 0;
  for (uint32_t i = 0; i < n; ++i) {
    const VertexId id = h.id(i);
    EXPECT_TRUE(ids.insert({id.tree, id.node}).second) << "duplicate id at node " << i;
    EXPECT_GE(id.depth(), previous_depth) << "not breadth-first at node " << i;
    previous_depth = id.depth();
    EXPECT_EQ(h.find(id), i);
    if (i < h.root_count) {
      EXPECT_EQ(h.parent[i], kNone);
      EXPECT_EQ(id, (VertexId{i, 1}));
      continue;
    }
    const uint32_t p = h.parent[i];
    ASSERT_LT(p, i);
    EXPECT_EQ(h.id(p), id.parent()) << "parent is not a right shift";
    EXPECT_EQ(h.first_child[p] + (id.node & 1), i);
    // Within a level, children of larger deviations first (the window ends sooner, build.cpp).
    if (i > h.root_count && h.id(i - 1).depth() == id.depth()) {
      const auto deviation = [&](uint32_t node) { return std::max(h.refine[node].mu, h.refine[node].delta); };
      EXPECT_GE(deviation(h.parent[i - 1]), deviation(p)) << "node " << i;
    }
  }
  // Children are derived, cut vertices are leaves outside the split node's subtree.
  for (uint32_t i = 0; i < n; ++i) {
    if (h.is_leaf(i)) {
      EXPECT_EQ(h.cut_left[i], kNone);
      EXPECT_EQ(h.cut_right[i], kNone);
      EXPECT_NE(h.leaf_vertex[i], kNone);
      continue;
    }
    const uint32_t c = h.first_child[i];
    EXPECT_EQ(h.id(c), h.id(i).child(0));
    EXPECT_EQ(h.id(c + 1), h.id(i).child(1));
    // v_u keeps v_s's position (half-edge collapse).
    EXPECT_EQ(distance(&h.position[3 * size_t(c + 1)], &h.position[3 * size_t(i)]), 0.0);
    EXPECT_TRUE(h.cut_left[i] != kNone || h.cut_right[i] != kNone);
    for (uint32_t cut : {h.cut_left[i], h.cut_right[i]}) {
      if (cut == kNone) continue;
      EXPECT_TRUE(h.is_leaf(cut));
      EXPECT_FALSE(is_ancestor_or_self(h.id(i), h.id(cut)));
    }
  }
  // Every node's decoded sphere and cone contain its children's (hence all descendants') as the builder
  // computes them. Nested info (the default) then rounds each child up under its parent's values
  // (builder/nested_refine_info.h): a child's sphere may reach outside its parent's, but no child's radius
  // is above its parent's (NestedRefineInfo.* checks that each node still holds its own bounds).
  const bool nested = built.stats.options.find("info=unnested") == std::string::npos;
  for (uint32_t i = 0; i < n; ++i) {
    if (h.is_leaf(i)) continue;
    const RefineBounds parent = dequantize_refine(h.refine[i], h.scale);
    for (uint32_t c : {h.first_child[i], h.first_child[i] + 1}) {
      const RefineBounds child = dequantize_refine(h.refine[c], h.scale);
      if (nested) {
        if (!never_refines(h.refine[c])) {
          EXPECT_GE(parent.radius, child.radius) << "sphere of node " << i;
        }
        continue;
      }
      const double shift = distance(&h.position[3 * size_t(c)], &h.position[3 * size_t(i)]);
      EXPECT_GE(parent.radius * (1 + 1e-6), child.radius + shift) << "sphere of node " << i;
      if (parent.cone_angle < 1.5707) {
        EXPECT_LE(angle(parent.axis, child.axis) + child.cone_angle, parent.cone_angle + 1e-5) << "cone of node " << i;
      }
      EXPECT_GE(parent.mu, child.mu);
      EXPECT_GE(parent.delta, child.delta);
    }
  }
  // Split order: a permutation of the internal nodes, parents before children.
  std::vector<int> position(n, -1);
  for (size_t k = 0; k < h.split_order.size(); ++k) {
    ASSERT_LT(h.split_order[k], n);
    ASSERT_EQ(position[h.split_order[k]], -1);
    position[h.split_order[k]] = int(k);
  }
  for (uint32_t i = h.root_count; i < n; ++i) {
    if (!h.is_leaf(i)) {
      EXPECT_LT(position[h.parent[i]], position[i]);
    }
  }
  // Leaf radii and cones cover the input faces around them.
  std::vector<uint32_t> leaf_node(mesh.vertex_count());
  for (uint32_t i = 0; i < n; ++i)
    if (h.is_leaf(i)) leaf_node[h.leaf_vertex[i]] = i;
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    const uint32_t* t = &mesh.indices[3 * f];
    const float* p[3] = {&mesh.positions[3 * size_t(t[0])], &mesh.positions[3 * size_t(t[1])],
                         &mesh.positions[3 * size_t(t[2])]};
    for (int k = 0; k < 3; ++k) {
      const RefineBounds b = dequantize_refine(h.refine[leaf_node[t[k]]], h.scale);
      EXPECT_GE(b.radius * (1 + 1e-6), distance(p[k], p[(k + 1) % 3]));
      EXPECT_GE(b.radius * (1 + 1e-6), distance(p[k], p[(k + 2) % 3]));
    }
  }
  // The base mesh is a valid oriented manifold too.
  Mesh base;
  for (uint32_t r = 0; r < h.root_count; ++r)
    base.positions.insert(base.positions.end(), &h.position[3 * r], &h.position[3 * r + 3]);
  base.indices = h.base_faces;
  std::string why;
  EXPECT_TRUE(is_oriented_manifold(base, &why)) << why;
}

TEST(Hierarchy, SphereBalanced) {
  const Mesh mesh = make_sphere(24, 32);
  BuildOptions options;
  options.base_vertices = 0;
  const BuildResult built = build_progressive_mesh(mesh, options);
  expect_valid_hierarchy(mesh, built);
  EXPECT_LE(built.stats.base_vertices, 8u) << "a closed sphere simplifies to a handful of vertices";
}

TEST(Hierarchy, SphereBalancedUnnestedSpheresAndConesNest) {
  const Mesh mesh = make_sphere(24, 32);
  BuildOptions options;
  options.base_vertices = 0;
  options.nested_info = false;
  expect_valid_hierarchy(mesh, build_progressive_mesh(mesh, options));
}

// The estimate drops only the chain's growth: the same hierarchy (the same ids; the packing within a level
// follows the deviation, so indices differ), spheres and cones, and a deviation space inside the bound's at
// every node (the chain's sum is at least the estimate's maximum, by induction).
TEST(Hierarchy, EstimatedDeviationIsInsideTheBound) {
  const Mesh mesh = make_terrain(8000);
  BuildOptions options;
  options.nested_info = false;  // nesting rounds each under its own parents: compare the measures themselves
  const BuildResult estimate = build_progressive_mesh(mesh, options);  // the default deviation
  options.deviation = Deviation::bound;
  const BuildResult bound = build_progressive_mesh(mesh, options);
  expect_valid_hierarchy(mesh, estimate);
  const Hierarchy &b = bound.hierarchy, &e = estimate.hierarchy;
  ASSERT_EQ(b.node_count(), e.node_count());
  size_t smaller = 0, internal = 0;
  for (uint32_t j = 0; j < e.node_count(); ++j) {
    const uint32_t i = b.find(e.id(j));
    ASSERT_NE(i, kNone) << "node " << j << " of the estimate's hierarchy is not in the bound's";
    ASSERT_EQ(b.is_leaf(i), e.is_leaf(j));
    const RefineInfo &x = b.refine[i], &y = e.refine[j];
    EXPECT_EQ(x.radius, y.radius);
    EXPECT_EQ(x.cone_angle, y.cone_angle);
    EXPECT_EQ(x.cone_x, y.cone_x);
    EXPECT_EQ(x.cone_y, y.cone_y);
    EXPECT_LE(y.mu, x.mu) << "node " << i;  // half-float bits of non-negative values order as the values
    EXPECT_LE(y.delta, x.delta) << "node " << i;
    if (b.is_leaf(i)) continue;
    ++internal;
    EXPECT_TRUE(y.mu > 0 || y.delta > 0) << "internal node " << i << " claims no error";
    smaller += y.mu < x.mu || y.delta < x.delta;
  }
  EXPECT_GT(smaller, internal / 2) << "the estimate should be tighter than the bound for most nodes";
  EXPECT_NE(estimate.stats.options.find("deviation=estimate"), std::string::npos);
  EXPECT_NE(bound.stats.options.find("deviation=bound"), std::string::npos);
}

TEST(Hierarchy, TorusGreedy) {
  const Mesh mesh = make_torus(24, 16, 1.0f, 0.3f);
  BuildOptions options;
  options.greedy = true;
  const BuildResult built = build_progressive_mesh(mesh, options);
  expect_valid_hierarchy(mesh, built);
}

TEST(Hierarchy, OpenGridKeepsItsBoundary) {
  const Mesh mesh = make_grid(30, 20);
  const BuildResult built = build_progressive_mesh(mesh);
  expect_valid_hierarchy(mesh, built);
  // One-sided (boundary) splits exist.
  const Hierarchy& h = built.hierarchy;
  size_t one_sided = 0;
  for (uint32_t i = 0; i < h.node_count(); ++i)
    one_sided += !h.is_leaf(i) && (h.cut_left[i] == kNone || h.cut_right[i] == kNone);
  EXPECT_GT(one_sided, 0u);
}

TEST(Hierarchy, BaseVerticesOptionStopsEarly) {
  const Mesh mesh = make_sphere(24, 32);
  BuildOptions options;
  options.base_vertices = 100;
  const BuildResult built = build_progressive_mesh(mesh, options);
  EXPECT_EQ(built.stats.base_vertices, 100u);
  expect_valid_hierarchy(mesh, built);
}

TEST(Hierarchy, BunnyBalancedIsShallow) {
  PMS_REQUIRE_SHARED_MODEL(path, "bunny.ply.xz");
  Mesh mesh = load_mesh(path.string());
  clean_mesh(mesh);
  const BuildResult built = build_progressive_mesh(mesh);
  expect_valid_hierarchy(mesh, built);
  EXPECT_LE(built.stats.tree_id_bits + built.stats.node_id_bits, 32u);
}

}  // namespace
}  // namespace pms
