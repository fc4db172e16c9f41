// Local refinement of multilevel meshes (gueziec et al. 1999, Fig. 14-15): the splits a region or a view
// brings in are a consistent subset of the DAG, the constraint counts are what a recount gives, the whole
// box is level 0 and an empty region the coarsest level, and every face names a vertex that is in, for
// edge-collapse builds and for (non-manifold) vertex-clustering builds.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <map>

#include "common/error.h"
#include "fixtures/view_models.h"
#include "io/shapes.h"
#include "multilevel/build.h"
#include "multilevel/cluster.h"
#include "multilevel/local.h"
#include "multilevel/region.h"

namespace pms {
namespace {

MultilevelMesh collapse_build(const test::BuiltModel& model, uint32_t levels) {
  return build_multilevel(model.input, collapses_of(model.h), levels);
}

MultilevelMesh collapse_build(uint32_t levels) { return collapse_build(test::built_sphere(), levels); }

MultilevelMesh cluster_build() {
  const Mesh torus = make_torus(48, 24, 2.0f, 0.5f);
  return build_multilevel_from_clusterings(torus, grid_clusterings(torus, std::vector<uint32_t>{16, 6, 2}));
}

void expect_consistent(const MultilevelDag& dag, const MultilevelRefinement& r) {
  for (uint32_t v = dag.top_vertices; v < dag.vertices; ++v) {
    uint32_t collapsed_prerequisites = 0, split_dependents = 0;
    for (uint32_t p : dag.prerequisites_of(v)) {
      collapsed_prerequisites += !r.is_split(p);
      if (r.is_split(v)) {
        ASSERT_TRUE(r.is_split(p)) << "split " << v << " without its prerequisite " << p;
      }
    }
    for (uint32_t d : dag.dependents_of(v)) split_dependents += r.is_split(d);
    ASSERT_EQ(r.split_constraints(v), collapsed_prerequisites) << v;
    ASSERT_EQ(r.collapse_constraints(v), split_dependents) << v;
  }
}

// Faces as multilevel vertex numbers, each rotated to start at its smallest, sorted.
std::vector<std::array<uint32_t, 3>> faces_of(std::span<const uint32_t> indices, std::span<const uint32_t> vertex) {
  std::vector<std::array<uint32_t, 3>> out;
  for (size_t i = 0; i < indices.size(); i += 3) {
    std::array<uint32_t, 3> f = {vertex[indices[i]], vertex[indices[i + 1]], vertex[indices[i + 2]]};
    std::rotate(f.begin(), std::min_element(f.begin(), f.end()), f.end());
    out.push_back(f);
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<std::array<uint32_t, 3>> lod_faces(const MultilevelMesh& m, uint32_t level) {
  MultilevelLod lod(m);
  lod.set_level(level);
  std::vector<uint32_t> identity(lod.vertex_count());
  for (uint32_t v = 0; v < identity.size(); ++v) identity[v] = v;
  return faces_of(lod.indices(), identity);
}

void expect_valid_mesh(const LocalMesh& local, const MultilevelRefinement& r, bool manifold) {
  std::map<std::pair<uint32_t, uint32_t>, int> directed;
  for (size_t i = 0; i < local.mesh.indices.size(); i += 3) {
    const uint32_t* c = &local.mesh.indices[i];
    for (int k = 0; k < 3; ++k) {
      ASSERT_LT(c[k], local.vertex.size());
      ASSERT_TRUE(r.is_split(local.vertex[c[k]])) << "a face names vertex " << local.vertex[c[k]] << ", which is out";
      ASSERT_NE(c[k], c[(k + 1) % 3]) << "degenerate face";
      ++directed[{c[k], c[(k + 1) % 3]}];
    }
  }
  if (!manifold) return;
  for (const auto& [edge, n] : directed)
    ASSERT_EQ(n, 1) << "edge " << edge.first << "-" << edge.second << " used " << n << " times";
}

float bounds(const MultilevelMesh& m, int axis, bool hi) {
  float b = m.positions[axis];
  for (uint32_t v = 0; v < m.vertices(); ++v) {
    const float x = m.positions[size_t(v) * m.dimension + axis];
    b = hi ? std::max(b, x) : std::min(b, x);
  }
  return b;
}

Region whole_box(const MultilevelMesh& m) {
  Region r;
  for (int k = 0; k < 3; ++k) r.lo[k] = bounds(m, k, false), r.hi[k] = bounds(m, k, true);
  return r;
}

void expect_local_refinement_works(const MultilevelMesh& m, bool manifold) {
  const MultilevelDag dag = build_multilevel_dag(m);
  MultilevelRefinement r(dag);
  expect_consistent(dag, r);
  // Empty region: the coarsest level.
  Region nowhere;
  nowhere.lo[0] = 1e30f;
  nowhere.hi[0] = 2e30f;
  EXPECT_TRUE(splits_in_region(m, dag, nowhere).empty());
  r.refine_to(splits_in_region(m, dag, nowhere));
  LocalMesh coarse = local_mesh(m, dag, r);
  EXPECT_EQ(faces_of(coarse.mesh.indices, coarse.vertex), lod_faces(m, m.level_count() - 1));
  // The whole box: level 0, and each intermediate level when refined down to it.
  for (uint32_t level = 0; level < m.level_count(); ++level) {
    r.refine_to(splits_in_region(m, dag, whole_box(m), level));
    expect_consistent(dag, r);
    EXPECT_EQ(r.split_count(), m.vertex_count[level] - dag.top_vertices);
    const LocalMesh uniform = local_mesh(m, dag, r);
    EXPECT_EQ(faces_of(uniform.mesh.indices, uniform.vertex), lod_faces(m, level)) << "level " << level;
  }
  // Half boxes and balls, refined from whatever was there before: consistent and valid.
  const Region box = whole_box(m);
  for (int axis = 0; axis < 3; ++axis) {
    Region half = box;
    half.hi[axis] = 0.5f * (box.lo[axis] + box.hi[axis]);
    r.refine_to(splits_in_region(m, dag, box));
    const MultilevelRefinement::Changes changes = r.refine_to(splits_in_region(m, dag, half));
    expect_consistent(dag, r);
    for (uint32_t v : splits_in_region(m, dag, half)) ASSERT_TRUE(r.is_split(v));
    EXPECT_GT(r.split_count(), 0u);
    EXPECT_LT(r.split_count(), dag.vertices - dag.top_vertices);
    EXPECT_FALSE(changes.collapses.empty());  // from level 0: the other half goes back to coarse
    expect_valid_mesh(local_mesh(m, dag, r), r, manifold);
    Region ball;
    ball.sphere = true;
    for (int k = 0; k < 3; ++k) ball.lo[k] = box.lo[k];
    ball.radius = 0.4f * (box.hi[axis] - box.lo[axis]);
    r.refine_to(splits_in_region(m, dag, ball, 1));
    expect_consistent(dag, r);
    expect_valid_mesh(local_mesh(m, dag, r), r, manifold);
  }
  // The splits come prerequisites first.
  MultilevelRefinement fresh(dag);
  for (uint32_t v : fresh.refine_to(splits_in_region(m, dag, box)).splits)
    for (uint32_t p : dag.prerequisites_of(v)) ASSERT_TRUE(fresh.is_split(p));
}

TEST(MultilevelLocal, EdgeCollapseBuild) { expect_local_refinement_works(collapse_build(0), true); }
// Merged levels too: a merged level numbers its vertices coarsest original level first and keeps parents of
// its own level as representatives, so the replay makes the builder's collapses (docs/internals.md, "Local
// refinement").
TEST(MultilevelLocal, EdgeCollapseBuildMergedLevels) {
  for (uint32_t levels : {3u, 6u}) {
    SCOPED_TRACE(std::to_string(levels) + " levels");
    expect_local_refinement_works(collapse_build(levels), true);
  }
}
TEST(MultilevelLocal, VertexClusteringBuild) { expect_local_refinement_works(cluster_build(), false); }

TEST(MultilevelLocal, SplitAndCollapseFollowTheConstraints) {
  const MultilevelMesh m = collapse_build(0);
  const MultilevelDag dag = build_multilevel_dag(m);
  MultilevelRefinement r(dag);
  // The finest vertex needs others first; its prerequisites, split in a topological order, let it in.
  const uint32_t finest = dag.vertices - 1;
  ASSERT_FALSE(dag.prerequisites_of(finest).empty());
  EXPECT_FALSE(r.can_split(finest));
  EXPECT_THROW(r.split(finest), Error);
  EXPECT_THROW(r.split(0), Error);  // top level: no collapse
  const std::vector<uint32_t> order = r.refine_to(std::vector<uint32_t>{finest}).splits;
  EXPECT_EQ(order.back(), finest);
  const uint32_t first_prerequisite = dag.prerequisites_of(finest)[0];
  if (dag.is_node(first_prerequisite)) {
    EXPECT_FALSE(r.can_collapse(first_prerequisite));
    EXPECT_GT(r.collapse_constraints(first_prerequisite), 0u);
  }
  r.collapse(finest);
  expect_consistent(dag, r);
  EXPECT_EQ(r.refine_to(std::vector<uint32_t>{}).collapses.size() + 1, order.size());
  EXPECT_EQ(r.split_count(), 0u);
}

// A view from nearby: some splits, not all, consistent, edge-manifold and consistently oriented.
void expect_view_refinement_works(const test::BuiltModel& model, const MultilevelMesh& m) {
  const MultilevelDag dag = build_multilevel_dag(m);
  MultilevelRefinement r(dag);
  for (float distance : {0.6f, 0.3f}) {
    const ViewParams view = test::view_for(model, test::framing_camera(model, {1, 0, 0.5f}, distance));
    r.refine_to(splits_for_view(m, dag, view, 1.0f));
    expect_consistent(dag, r);
    EXPECT_GT(r.split_count(), 0u);
    EXPECT_LT(r.split_count(), dag.vertices - dag.top_vertices);
    expect_valid_mesh(local_mesh(m, dag, r), r, true);
  }
}

// Hoppe 1997 §4.2's back-face test: a surface is refined where it faces the eye. A terrain seen from below
// wants almost nothing of what it wants from above; a closed surface wants little of its far side, and that
// little only where a split's star is wide enough to bend round (a cone of 90° or more is never culled).
TEST(MultilevelLocal, ViewDoesNotRefineWhatFacesAway) {
  const test::BuiltModel& terrain = test::built_terrain();
  const MultilevelMesh land = collapse_build(terrain, 0);
  const MultilevelDag land_dag = build_multilevel_dag(land);
  const auto wanted_from = [&](const test::BuiltModel& model, const MultilevelMesh& m, const MultilevelDag& dag,
                               std::array<float, 3> direction, float distance) {
    return splits_for_view(m, dag, test::view_for(model, test::framing_camera(model, direction, distance)), 1.0f);
  };
  const size_t above = wanted_from(terrain, land, land_dag, {0.2f, 0.1f, 1}, 0.8f).size();
  const size_t below = wanted_from(terrain, land, land_dag, {0.2f, 0.1f, -1}, 0.8f).size();
  EXPECT_GT(above, 100u);
  EXPECT_LT(below * 10, above) << "from below, the terrain's faces all face away";

  const test::BuiltModel& sphere = test::built_sphere();
  const MultilevelMesh m = collapse_build(sphere, 0);
  const MultilevelDag dag = build_multilevel_dag(m);
  float centre[3] = {0, 0, 0};
  for (int k = 0; k < 3; ++k) centre[k] = 0.5f * (sphere.h.bbox_min[k] + sphere.h.bbox_max[k]);
  const float radius = 0.5f * (sphere.h.bbox_max[0] - sphere.h.bbox_min[0]);
  for (const float side : {1.0f, -1.0f}) {
    SCOPED_TRACE(side > 0 ? "eye on +x" : "eye on -x");
    uint32_t near_side = 0, far_side = 0;
    for (uint32_t v : wanted_from(sphere, m, dag, {side, 0, 0}, 1.5f)) {
      float p[3];
      m.point(v, p);
      const float along = side * (p[0] - centre[0]);  // towards the eye
      near_side += along > 0.3f * radius;
      if (along < -0.3f * radius) {
        ++far_side;
        const float sin2 = dag.cone[4 * size_t(v - dag.top_vertices) + 3];
        EXPECT_GT(sin2, 0.1f) << "a narrow cone facing away was not culled";
      }
    }
    EXPECT_GT(near_side, 0u);
    EXPECT_LT(far_side * 10, near_side);
  }
}

TEST(MultilevelLocal, ViewRefinesNearTheEyeMore) {
  const test::BuiltModel& terrain = test::built_terrain();
  expect_view_refinement_works(terrain, collapse_build(terrain, 0));
  expect_view_refinement_works(terrain, collapse_build(terrain, 6));
}

TEST(MultilevelLocal, BunnyMergedLevels) {
  const test::BuiltModel* bunny = test::built_bunny();
  if (!bunny) GTEST_SKIP() << "../shared/models/bunny.ply.xz not found: this test needs the shared test meshes";
  const MultilevelMesh m = collapse_build(*bunny, 8);
  expect_local_refinement_works(m, true);
  expect_view_refinement_works(*bunny, m);
}

}  // namespace
}  // namespace pms
