// The DAG of vsplit / ecol operations (Zheng & Chan 2006 §3) and its traversals (§4–5) on built models:
// every operation a cut allows is legal on the selectively refined mesh (SelectiveMesh applies it alone,
// without a forced chain, and keeps its invariants), every dependency edge is needed, counters and fronts
// equal a recount after random and view-driven sequences, BUDGET mode never exceeds the budget, and at
// convergence the traversals give the adaptation loop's mesh of the view.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "common/error.h"
#include "dag/compact.h"
#include "dag/cut.h"
#include "dag/dag.h"
#include "dag/traversal.h"
#include "fixtures/view_models.h"
#include "spm/adapt.h"
#include "spm/criteria.h"
#include "spm/hierarchy.h"
#include "spm/selective_mesh.h"
#include "spm/vertex_hierarchy.h"
#include "test_support.h"

namespace pms {
namespace {

using test::BuiltModel;
using test::IdFace;

std::string audit(const DagCut& cut) {
  std::string why;
  return cut.check(&why) ? "ok" : why;
}

std::string invariants(const SelectiveMesh& mesh) {
  std::string why;
  return mesh.check_invariants(&why) ? "ok" : why;
}

// The client's mesh: a SelectiveMesh over the complete hierarchy that applies a cut's operations.
struct Mirror {
  const Dag& dag;
  VertexHierarchy hierarchy;
  SelectiveMesh mesh;
  std::vector<uint32_t> slot;  // per DAG node

  Mirror(const BuiltModel& model, const Dag& d)
      : dag(d), hierarchy(test::complete_hierarchy(model.model())), mesh(hierarchy, model.model().base_faces) {
    const ModelData m = model.model();
    for (uint32_t n = 0; n < dag.size(); ++n) slot.push_back(hierarchy.find(m.id(dag.model_node(n))));
  }

  // A split must need no forced chain: exactly one vertex more.
  void apply(const DagOp& op) {
    const size_t before = mesh.vertex_count();
    if (op.split) {
      const VSplitResult r = mesh.vsplit(slot[op.node]);
      ASSERT_TRUE(r.done) << "split of DAG node " << op.node;
      ASSERT_EQ(mesh.vertex_count(), before + 1) << "the split of DAG node " << op.node << " needed a forced chain";
    } else {
      ASSERT_TRUE(mesh.ecol(slot[op.node])) << "SelectiveMesh refused the collapse of DAG node " << op.node;
    }
  }
  void apply(const std::vector<DagOp>& ops) {
    for (const DagOp& op : ops) {
      apply(op);
      if (::testing::Test::HasFatalFailure()) return;
    }
  }
};

// Splits n and everything it needs, each as it reaches Fs (the order of the traversals' forced splits).
void split_closure(DagCut& cut, uint32_t n, std::vector<DagOp>& ops) {
  while (!cut.is_split(n)) {
    uint32_t y = n;
    while (!cut.in_fs(y)) {
      const auto parents = cut.dag().parents(y);
      y = *std::find_if(parents.begin(), parents.end(), [&](uint32_t p) { return !cut.is_split(p); });
    }
    cut.split(y);
    ops.push_back({y, true});
  }
}

std::vector<Camera> route_of(const BuiltModel& model) {
  std::vector<Camera> route;
  route.push_back(test::framing_camera(model, {0.3f, 0.2f, 1}, 4));
  route.push_back(test::framing_camera(model, {1, 0.5f, 0.4f}, 1));
  for (int i = 0; i <= 6; ++i) {  // moving close, sweeping around
    const float a = 0.35f * float(i);
    route.push_back(
        test::framing_camera(model, {std::sin(a), 0.3f - 0.1f * float(i), std::cos(a)}, 1.0f - 0.1f * float(i)));
  }
  route.push_back(test::framing_camera(model, {1, 0.05f, -0.2f}, 0.6f, 30));
  route.push_back(test::framing_camera(model, {-0.4f, 0.3f, 1}, 0.35f));
  route.push_back(test::framing_camera(model, {0.3f, 0.2f, 1}, 3));
  return route;
}

std::vector<IdFace> adapt_mesh(const BuiltModel& model, const ViewParams& view, float tolerance) {
  const ModelData m = model.model();
  VertexHierarchy h = test::complete_hierarchy(m);
  SelectiveMesh mesh(h, m.base_faces);
  AdaptOptions options;
  options.tolerance = tolerance;
  SelectiveRefinement refinement(mesh, m.scale, options);
  refinement.set_view(view);
  refinement.converge();
  return test::id_faces(mesh);
}

// MANAGE-TRAVERSAL with no limits until a frame changes nothing.
void converge(DagTraverser& traverser, DagTraversal traversal, Mirror& mirror) {
  DagManageOptions options;
  options.traversal = traversal;
  options.max_ops = 0;
  for (int frame = 0; frame < 200; ++frame) {
    std::vector<DagOp> ops;
    traverser.manage(options, ops);
    mirror.apply(ops);
    if (::testing::Test::HasFatalFailure() || ops.empty()) return;
  }
  ADD_FAILURE() << "no convergence in 200 frames";
}

void expect_sound_edges(const BuiltModel& model) {
  const ModelData m = model.model();
  const Dag dag(m);
  const DagStats& s = dag.stats();
  std::printf(
      "[ dag ] %s: %u nodes, %.4f edges per node (%llu parent, %llu dependency; redundant: %llu ancestor, "
      "%llu dependency, %llu parent), max out-degree %u, %.1f ms, %.1f B per node shared\n",
      model.name.c_str(), s.nodes, s.edges_per_node(), (unsigned long long)s.parent_edges,
      (unsigned long long)s.dependency_edges, (unsigned long long)s.redundant_ancestor,
      (unsigned long long)s.redundant_dependency, (unsigned long long)s.redundant_parent, s.max_children,
      1e3 * s.seconds, double(dag.memory_bytes()) / s.nodes);
  ASSERT_GT(s.nodes, 0u);
  uint64_t edges = 0;
  for (uint32_t n = 0; n < dag.size(); ++n) {
    const auto parents = dag.parents(n);
    ASSERT_LE(parents.size(), 2u);
    edges += parents.size();
    for (uint32_t p : parents) {
      const auto kids = dag.children(p);
      EXPECT_NE(std::find(kids.begin(), kids.end(), n), kids.end()) << "out-edges are not the in-edges reversed";
      if (p != dag.hierarchy_parent(n)) {  // a dependency: never an ancestor (those are split anyway)
        EXPECT_FALSE(is_ancestor_or_self(m.id(dag.model_node(p)), m.id(dag.model_node(n))));
      }
    }
    if (dag.hierarchy_parent(n) == kNone) {
      EXPECT_NE(std::find(dag.roots().begin(), dag.roots().end(), n), dag.roots().end());
    }
  }
  EXPECT_EQ(edges, s.parent_edges + s.dependency_edges);
  // Every dependency edge w -> n is needed: with everything else n needs split and w collapsed, n's cut
  // vertices share their active ancestor, so n alone cannot split.
  int checked = 0;
  for (uint32_t n = 0; n < dag.size() && checked < 30; ++n) {
    const uint32_t p = dag.hierarchy_parent(n);
    const auto parents = dag.parents(n);
    if (p == kNone || parents.size() != 2) continue;
    const uint32_t w = parents[0] == p ? parents[1] : parents[0];
    DagCut cut(dag);
    Mirror mirror(model, dag);
    std::vector<DagOp> ops;
    split_closure(cut, p, ops);
    mirror.apply(ops);
    ASSERT_FALSE(::testing::Test::HasFatalFailure());
    ASSERT_FALSE(cut.is_split(w)) << "the parent's requirements hold the dependency: a redundant edge";
    ASSERT_TRUE(cut.is_candidate(n) && !cut.in_fs(n));
    const uint32_t mn = dag.model_node(n);
    EXPECT_EQ(mirror.mesh.active_ancestor(m.id(m.cut_left[mn])), mirror.mesh.active_ancestor(m.id(m.cut_right[mn])))
        << "node " << n << " could split without its dependency " << w;
    ++checked;
  }
  if (s.dependency_edges > 0) {
    EXPECT_GT(checked, 0);
  }
}

TEST(Dag, EdgesAreSoundAndNeededSphere) { expect_sound_edges(test::built_sphere()); }
TEST(Dag, EdgesAreSoundAndNeededTerrain) { expect_sound_edges(test::built_terrain()); }
TEST(Dag, EdgesAreSoundAndNeededBunny) {
  PMS_REQUIRE_SHARED_MODEL(path, "bunny.ply.xz");
  expect_sound_edges(*test::built_bunny());
}

// No edge is implied by another path: on a small model, the closure over the other in-edge never holds
// an edge's source (brute force over the reduced graph, which has the same closures).
TEST(Dag, NoRedundantEdgeSphere) {
  const Dag dag(test::built_sphere().model());
  std::vector<uint32_t> seen(dag.size(), kNone), stack;
  for (uint32_t n = 0; n < dag.size(); ++n) {
    const auto parents = dag.parents(n);
    for (uint32_t a : parents)
      for (uint32_t b : parents) {
        if (a == b) continue;
        stack.assign(1, b);  // is a required by b?
        bool found = false;
        while (!stack.empty() && !found) {
          const uint32_t y = stack.back();
          stack.pop_back();
          if (seen[y] == n * 2 + (a < b)) continue;
          seen[y] = n * 2 + (a < b);
          found = y == a;
          for (uint32_t q : dag.parents(y)) stack.push_back(q);
        }
        EXPECT_FALSE(found) << "edge " << a << " -> " << n << " is implied through " << b;
      }
  }
}

// Random legal operations from the fronts: the mesh accepts each one alone and stays valid, and the cut's
// counters, fronts and triangle count equal a recount.
void expect_random_operations_legal(const BuiltModel& model, int steps, uint32_t seed,
                                    uint32_t inline_limit = DagCut::kInlineLimit) {
  const Dag dag(model.model());
  DagCut cut(dag, inline_limit);
  Mirror mirror(model, dag);
  std::mt19937 rng(seed);
  for (int step = 0; step < steps; ++step) {
    const bool split = std::uniform_int_distribution<int>(0, 99)(rng) < (step < steps / 2 ? 75 : 35);
    // The first front node at or after a random node (wrapping): not uniform over the front, but any front
    // node can come, and it costs a scan to the next one rather than a list of the whole front per step.
    const auto in_front = [&](uint32_t n) { return split ? cut.in_fs(n) : cut.in_fc(n); };
    const auto next = [&](uint32_t from) { return split ? cut.next_candidate(from) : cut.next_fc(from); };
    const uint32_t start = std::uniform_int_distribution<uint32_t>(0, dag.size() - 1)(rng);
    uint32_t n = kNone;
    for (uint32_t m = next(start); m != kNone && n == kNone; m = next(m + 1))
      if (in_front(m)) n = m;
    for (uint32_t m = next(0); m != kNone && m < start && n == kNone; m = next(m + 1))
      if (in_front(m)) n = m;
    if (n == kNone) continue;
    if (split) cut.split(n);
    else cut.collapse(n);
    mirror.apply({n, split});
    ASSERT_FALSE(::testing::Test::HasFatalFailure());
    ASSERT_EQ(mirror.mesh.face_count(), cut.triangles());
    if (step % 97 == 0) {
      ASSERT_EQ(audit(cut), "ok") << "step " << step;
      ASSERT_EQ(invariants(mirror.mesh), "ok") << "step " << step;
    }
  }
  EXPECT_EQ(audit(cut), "ok");
  EXPECT_EQ(invariants(mirror.mesh), "ok");
  EXPECT_GT(cut.split_count(), 0u);
}

TEST(Dag, RandomOperationsAreLegalSphere) { expect_random_operations_legal(test::built_sphere(), 6000, 1); }
TEST(Dag, RandomOperationsAreLegalTerrain) { expect_random_operations_legal(test::built_terrain(), 20000, 2); }
TEST(Dag, RandomOperationsAreLegalStuddedPlane) {
  expect_random_operations_legal(test::built_studded_plane(), 6000, 3);
}
// Counters in the side table (every node with a DAG child or parent there) behave the same.
TEST(Dag, RandomOperationsAreLegalWithSideTableCountersTerrain) {
  expect_random_operations_legal(test::built_terrain(), 20000, 5, 0);
}
TEST(Dag, RandomOperationsAreLegalWithSomeSideTableCountersSphere) {
  expect_random_operations_legal(test::built_sphere(), 6000, 6, 1);
}
TEST(Dag, RandomOperationsAreLegalBunny) {
  PMS_REQUIRE_SHARED_MODEL(path, "bunny.ply.xz");
  expect_random_operations_legal(*test::built_bunny(), 40000, 4);
}

// A route flown with each traversal and mode: every frame's operations are legal, the cut stays
// consistent, BUDGET never exceeds the budget; then, converged at the last view with the same
// traversal, the mesh is the adaptation loop's (priority always; linear and constant-time from the base).
void expect_route(const BuiltModel& model, DagTraversal traversal, DagMode mode, uint32_t n_ops, float tolerance,
                  uint32_t inline_limit = DagCut::kInlineLimit) {
  const Dag dag(model.model());
  DagCut cut(dag, inline_limit);
  Mirror mirror(model, dag);
  DagTraverser traverser(cut);
  DagManageOptions options;
  options.traversal = traversal;
  options.mode = mode;
  options.max_ops = n_ops;
  const std::vector<Camera> route = route_of(model);
  // A budget the close views want more than (their converged mesh size, halved) and the route reaches
  // with N operations per frame (from the base mesh at N = 17, constant-time spends up to half its split
  // evaluations on its watch list and grows more slowly than the others: ~16 N triangles on bunny).
  options.budget =
      std::min<uint64_t>(adapt_mesh(model, test::view_for(model, route[route.size() - 2]), tolerance).size() / 2,
                         dag.base_faces() + 2 * 12 * uint64_t(n_ops));
  uint64_t ops_total = 0;
  bool budget_stopped = false;
  for (const Camera& camera : route) {
    traverser.set_view(make_criteria(test::view_for(model, camera), tolerance));
    for (int frame = 0; frame < 4; ++frame) {
      std::vector<DagOp> ops;
      const size_t queued = cut.fc_size() + cut.candidate_count();
      const DagFrameStats stats = traverser.manage(options, ops);
      mirror.apply(ops);
      ASSERT_FALSE(::testing::Test::HasFatalFailure());
      ops_total += ops.size();
      if (traversal != DagTraversal::priority) {  // each front or new front node evaluated once at most
        ASSERT_LE(stats.evaluated, queued + ops.size() * (3 + dag.stats().max_children));
      }
      budget_stopped |= stats.stopped_by_budget;
      ASSERT_EQ(stats.splits + stats.collapses, ops.size());
      if (traversal != DagTraversal::constant_time && n_ops) {
        ASSERT_LE(stats.splits, n_ops);
        ASSERT_LE(stats.collapses, n_ops);
      }
      if (traversal == DagTraversal::constant_time && n_ops) {
        ASSERT_LE(stats.evaluated, 2 * n_ops);
      }
      ASSERT_EQ(mirror.mesh.face_count(), cut.triangles());
      if (mode == DagMode::budget) {
        ASSERT_LE(cut.triangles(), options.budget);
      }
      ASSERT_EQ(audit(cut), "ok");
    }
    ASSERT_EQ(invariants(mirror.mesh), "ok");
  }
  EXPECT_GT(ops_total, 0u);
  if (mode == DagMode::budget) {
    EXPECT_TRUE(budget_stopped) << "the budget never bound: the test checks nothing";
  }
  if (mode == DagMode::free && traversal == DagTraversal::priority) {
    const ViewParams last = test::view_for(model, route.back());
    converge(traverser, traversal, mirror);
    EXPECT_EQ(audit(cut), "ok");
    EXPECT_TRUE(test::id_faces(mirror.mesh) == adapt_mesh(model, last, tolerance))
        << "priority at convergence is not the adaptation loop's mesh";
    // And then the close view, from where the route left the cut.
    const ViewParams close = test::view_for(model, route[route.size() - 2]);
    traverser.set_view(make_criteria(close, tolerance));
    converge(traverser, traversal, mirror);
    EXPECT_TRUE(test::id_faces(mirror.mesh) == adapt_mesh(model, close, tolerance));
  }
}

void expect_every_route(const BuiltModel& model, float tolerance) {
  for (DagTraversal traversal : {DagTraversal::priority, DagTraversal::linear, DagTraversal::constant_time})
    for (DagMode mode : {DagMode::free, DagMode::budget})
      for (uint32_t n : {300u, 17u}) {
        SCOPED_TRACE("traversal " + std::to_string(int(traversal)) + " mode " + std::to_string(int(mode)) + " N " +
                     std::to_string(n));
        expect_route(model, traversal, mode, n, tolerance);
        if (::testing::Test::HasFatalFailure()) return;
      }
}

TEST(DagTraversal, RoutesSphere) { expect_every_route(test::built_sphere(), 0.5f); }
TEST(DagTraversal, RoutesTerrain) { expect_every_route(test::built_terrain(), 1); }
TEST(DagTraversal, RoutesWithSideTableCountersTerrain) {
  expect_route(test::built_terrain(), DagTraversal::priority, DagMode::budget, 300, 1, 1);
  expect_route(test::built_terrain(), DagTraversal::priority, DagMode::free, 300, 1, 0);
  expect_route(test::built_terrain(), DagTraversal::linear, DagMode::free, 300, 1, 1);
}
TEST(DagTraversal, RoutesBunny) {
  PMS_REQUIRE_SHARED_MODEL(path, "bunny.ply.xz");
  expect_every_route(*test::built_bunny(), 1);
}

// From the base mesh every traversal converges to the adaptation loop's mesh: the local rule's fixed
// point reached by splits only is the target itself.
void expect_from_base(const BuiltModel& model, float tolerance) {
  const Dag dag(model.model());
  for (const Camera& camera : route_of(model)) {
    const ViewParams view = test::view_for(model, camera);
    const std::vector<IdFace> target = adapt_mesh(model, view, tolerance);
    for (DagTraversal traversal : {DagTraversal::priority, DagTraversal::linear, DagTraversal::constant_time}) {
      DagCut cut(dag);
      Mirror mirror(model, dag);
      DagTraverser traverser(cut);
      traverser.set_view(make_criteria(view, tolerance));
      converge(traverser, traversal, mirror);
      ASSERT_FALSE(::testing::Test::HasFatalFailure());
      EXPECT_TRUE(test::id_faces(mirror.mesh) == target) << "traversal " << int(traversal);
      EXPECT_EQ(audit(cut), "ok");
    }
  }
}

TEST(DagTraversal, FromBaseEqualsAdaptSphere) { expect_from_base(test::built_sphere(), 0.5f); }
TEST(DagTraversal, FromBaseEqualsAdaptTerrain) { expect_from_base(test::built_terrain(), 1); }
TEST(DagTraversal, FromBaseEqualsAdaptBunny) {
  PMS_REQUIRE_SHARED_MODEL(path, "bunny.ply.xz");
  expect_from_base(*test::built_bunny(), 1);
}

// converge() (a DAG session's first answer) reaches the adaptation loop's mesh in one call, from the base
// mesh and from a cut another view left, whatever traversal the options name; in BUDGET mode it never
// exceeds the budget; a second call changes nothing.
void expect_converge(const BuiltModel& model, float tolerance) {
  const Dag dag(model.model());
  const std::vector<Camera> route = route_of(model);
  for (DagTraversal traversal : {DagTraversal::priority, DagTraversal::linear, DagTraversal::constant_time}) {
    SCOPED_TRACE(int(traversal));
    DagCut cut(dag);
    Mirror mirror(model, dag);
    DagTraverser traverser(cut);
    DagManageOptions options;
    options.traversal = traversal;
    for (size_t i : {size_t(2), route.size() - 2}) {
      const ViewParams view = test::view_for(model, route[i]);
      traverser.set_view(make_criteria(view, tolerance));
      std::vector<DagOp> ops;
      const DagFrameStats stats = traverser.converge(options, ops);
      mirror.apply(ops);
      ASSERT_FALSE(::testing::Test::HasFatalFailure());
      EXPECT_EQ(stats.splits + stats.collapses, ops.size());
      EXPECT_GT(stats.splits, options.max_ops) << "not limited by N";
      EXPECT_TRUE(test::id_faces(mirror.mesh) == adapt_mesh(model, view, tolerance)) << "view " << i;
      ASSERT_EQ(audit(cut), "ok");
      std::vector<DagOp> again;
      traverser.converge(options, again);
      EXPECT_TRUE(again.empty());
    }
  }
  // BUDGET mode: the converged cut stops at the budget, the most visible splits first.
  DagCut cut(dag);
  DagTraverser traverser(cut);
  traverser.set_view(make_criteria(test::view_for(model, route[route.size() - 2]), tolerance));
  DagManageOptions options;
  options.mode = DagMode::budget;
  options.budget = dag.base_faces() + 2 * 450;
  std::vector<DagOp> ops;
  const DagFrameStats stats = traverser.converge(options, ops);
  EXPECT_TRUE(stats.stopped_by_budget);
  EXPECT_LE(cut.triangles(), options.budget);
  EXPECT_GT(cut.triangles(), options.budget - 8);
  EXPECT_EQ(audit(cut), "ok");
}

TEST(DagTraversal, ConvergeIsTheAdaptationLoopsMeshTerrain) { expect_converge(test::built_terrain(), 1); }
TEST(DagTraversal, ConvergeIsTheAdaptationLoopsMeshBunny) {
  PMS_REQUIRE_SHARED_MODEL(path, "bunny.ply.xz");
  expect_converge(*test::built_bunny(), 1);
}

// The terrain's DAG, a cut of it with its mirror mesh, and a traverser viewing it from afar.
struct FarTerrain {
  const BuiltModel& model = test::built_terrain();
  const Dag dag{model.model()};
  DagCut cut{dag};
  Mirror mirror{model, dag};
  DagTraverser traverser{cut};
  FarTerrain() {
    traverser.set_view(make_criteria(test::view_for(model, test::framing_camera(model, {0.3f, 0.2f, 1}, 4)), 1));
  }
};

// The same, viewed close and low.
struct CloseTerrain : FarTerrain {
  CloseTerrain() {
    traverser.set_view(
        make_criteria(test::view_for(model, test::framing_camera(model, {1, 0.3f, 0.08f}, 0.45f, 60)), 1));
  }
};

// A capped convergence stops at the cap with a legal cut, and the rest of the way is ordinary frames.
TEST(DagTraversal, ConvergeStopsAtItsOperationCap) {
  FarTerrain t;
  auto& [model, dag, cut, mirror, traverser] = t;
  std::vector<DagOp> ops;
  traverser.converge({}, ops, 25);
  EXPECT_EQ(ops.size(), 25u);
  mirror.apply(ops);
  EXPECT_EQ(audit(cut), "ok");
  ops.clear();
  traverser.converge({}, ops);
  EXPECT_GT(ops.size(), 0u) << "the cap left work for later";
  mirror.apply(ops);
  EXPECT_EQ(audit(cut), "ok");
}

// Constant-time evaluates its own operations' new front nodes first: with a queue far longer than N, the
// paper's FIFO (new nodes at the back) would never split, within one call, a child of a split of that call;
// here most of a call's splits after its first wanted one are such children, and it still evaluates at
// most N nodes a phase.
TEST(DagTraversal, ConstantTimeFollowsItsOwnChangesFirst) {
  FarTerrain t;
  auto& [model, dag, cut, mirror, traverser] = t;
  std::vector<DagOp> ops;
  traverser.converge({}, ops);
  mirror.apply(ops);
  traverser.set_view(make_criteria(test::view_for(model, test::framing_camera(model, {-0.4f, 0.3f, 1}, 0.35f)), 1));
  DagManageOptions options;
  options.traversal = DagTraversal::constant_time;
  options.max_ops = 40;
  uint32_t splits = 0, cascaded = 0;
  for (int frame = 0; frame < 10; ++frame) {
    ASSERT_GT(cut.candidate_count(), 4 * options.max_ops) << "a front the sweep would not wrap in one call";
    ops.clear();
    const DagFrameStats stats = traverser.manage(options, ops);
    mirror.apply(ops);
    ASSERT_FALSE(::testing::Test::HasFatalFailure());
    ASSERT_LE(stats.evaluated, 2 * options.max_ops);
    std::vector<uint32_t> split_here;
    for (const DagOp& op : ops) {
      if (!op.split) continue;
      const uint32_t p = dag.hierarchy_parent(op.node);
      if (!split_here.empty()) {
        ++splits;
        cascaded += std::find(split_here.begin(), split_here.end(), p) != split_here.end();
      }
      split_here.push_back(op.node);
    }
  }
  EXPECT_EQ(audit(cut), "ok");
  EXPECT_GT(splits, 50u);
  EXPECT_GT(2 * cascaded, splits) << cascaded << " of " << splits << " splits are children of the call's own";
}

// Constant-time watches the candidates it found not needing a split yet (the whole front of its converged
// first view, then what it evaluates), at most DagTraverser::watch_limit, each a candidate, kept through the
// compact cut; as the eye moves closer, the ones predicted to need a split now are evaluated before the
// sweep: with the same cut, cursors, view and N, the watching traverser splits more than one whose list
// was emptied, and each evaluates at most N nodes a phase.
TEST(DagTraversal, ConstantTimeWatchesWhatTheViewWillNeed) {
  const BuiltModel& model = test::built_terrain();
  const Dag dag(model.model());
  DagCut cut(dag);
  DagTraverser traverser(cut);
  DagManageOptions options;
  options.traversal = DagTraversal::constant_time;
  options.max_ops = 20;
  traverser.set_view(make_criteria(test::view_for(model, test::framing_camera(model, {0.3f, 0.2f, 1}, 1.2f)), 1));
  std::vector<DagOp> ops;
  traverser.converge(options, ops);
  ASSERT_FALSE(cut.watch().empty());
  ASSERT_LE(cut.watch().size(), DagTraverser::watch_limit(dag.size(), options.max_ops));
  for (const DagCut::Watch& w : cut.watch()) {
    ASSERT_TRUE(cut.is_candidate(w.node()));
    ASSERT_TRUE(cut.watched(w.node()));
  }
  // Through the compact form, as a session keeps it: the same list.
  const CompactDagCut compact(cut);
  EXPECT_GE(compact.memory_bytes(), cut.watch().size() * sizeof(DagCut::Watch));
  const DagCut loaded = compact.dense(dag);
  ASSERT_EQ(loaded.watch().size(), cut.watch().size());
  for (size_t i = 0; i < cut.watch().size(); ++i) {
    EXPECT_EQ(loaded.watch()[i].code, cut.watch()[i].code);
    EXPECT_EQ(loaded.watch()[i].key, cut.watch()[i].key);
  }
  DagCut blind = compact.dense(dag);  // the same cut and cursors, nothing watched
  for (const DagCut::Watch& w : blind.watch()) blind.set_watched(w.node(), false);
  blind.watch().clear();
  DagTraverser blind_traverser(blind);
  uint32_t watching_splits = 0, blind_splits = 0;
  for (int frame = 0; frame < 6; ++frame) {
    const float distance = 1.2f - 0.1f * float(frame + 1);  // approaching
    const ViewCriteria view =
        make_criteria(test::view_for(model, test::framing_camera(model, {0.3f, 0.2f, 1}, distance)), 1);
    traverser.set_view(view);
    blind_traverser.set_view(view);
    ops.clear();
    DagFrameStats stats = traverser.manage(options, ops);
    ASSERT_LE(stats.evaluated, 2 * options.max_ops);
    watching_splits += stats.splits;
    ops.clear();
    stats = blind_traverser.manage(options, ops);
    ASSERT_LE(stats.evaluated, 2 * options.max_ops);
    blind_splits += stats.splits;
    ASSERT_LE(cut.watch().size(), DagTraverser::watch_limit(dag.size(), options.max_ops));
  }
  EXPECT_EQ(audit(cut), "ok");
  EXPECT_GT(watching_splits, blind_splits + blind_splits / 4) << watching_splits << " against " << blind_splits;
}

// Constant-time evaluates at most N nodes per phase, however large the front.
TEST(DagTraversal, ConstantTimeEvaluatesAtMostN) {
  const BuiltModel& model = test::built_terrain();
  const Dag dag(model.model());
  DagCut cut(dag);
  DagTraverser traverser(cut);
  traverser.set_view(make_criteria(test::view_for(model, test::framing_camera(model, {0.1f, 0.2f, 1}, 0.8f)), 0.5f));
  DagManageOptions options;
  options.traversal = DagTraversal::constant_time;
  options.max_ops = 40;
  uint32_t frames_with_work = 0;
  for (int frame = 0; frame < 60; ++frame) {
    std::vector<DagOp> ops;
    const DagFrameStats stats = traverser.manage(options, ops);
    ASSERT_LE(stats.evaluated, 2 * options.max_ops);  // two phases
    frames_with_work += !ops.empty();
  }
  EXPECT_GT(frames_with_work, 30u);
  EXPECT_GT(cut.split_count(), 500u);
  EXPECT_EQ(audit(cut), "ok");
}

// A hand-made model's bad links are refused, and a cut refuses operations its fronts do not allow.
TEST(Dag, RefusesBadModelsAndIllegalOperations) {
  const BuiltModel& model = test::built_sphere();
  uint32_t internal = kNone;
  for (uint32_t n = 0; n < model.h.node_count() && internal == kNone; ++n)
    if (!model.h.is_leaf(n) && model.h.cut_left[n] != kNone) internal = n;
  ASSERT_NE(internal, kNone);
  {
    Hierarchy h = model.h;
    h.cut_left[internal] = uint32_t(h.node_count() + 7);
    EXPECT_THROW(Dag{model_of(h)}, Error);
  }
  {
    Hierarchy h = model.h;
    h.cut_left[internal] = h.cut_right[internal] = kNone;
    EXPECT_THROW(Dag{model_of(h)}, Error);
  }
  {
    Hierarchy h = model.h;
    h.parent[internal] = uint32_t(h.node_count());
    EXPECT_THROW(Dag{model_of(h)}, Error);
  }
  const Dag dag(model.model());
  DagCut cut(dag);
  const uint32_t root = dag.roots()[0];
  EXPECT_THROW(cut.collapse(root), Error);  // not split
  uint32_t below = kNone;
  for (uint32_t n = 0; n < dag.size() && below == kNone; ++n)
    if (dag.hierarchy_parent(n) != kNone) below = n;
  EXPECT_THROW(cut.split(below), Error);  // its parent is collapsed
  DagTraverser traverser(cut);
  std::vector<DagOp> ops;
  EXPECT_THROW(traverser.manage({}, ops), Error);  // no view
  EXPECT_EQ(audit(cut), "ok");
}

// A cut's split nodes, and the same without one node another split node needs (no cut).
struct SplitSets {
  std::vector<uint32_t> split, holed;
};
SplitSets split_sets(const DagCut& cut) {
  SplitSets sets;
  for (uint32_t n = 0; n < cut.dag().size(); ++n)
    if (cut.is_split(n)) sets.split.push_back(n);
  uint32_t needed = kNone;
  for (uint32_t n : sets.split)
    if (!cut.in_fc(n)) needed = n;
  for (uint32_t n : sets.split)
    if (n != needed) sets.holed.push_back(n);
  return sets;
}

// A cut rebuilt from its split nodes alone (what a resuming client's mesh tells) is the same cut; a set
// that is not a cut is refused.
TEST(Dag, CutRebuildsFromItsSplitNodes) {
  CloseTerrain t;
  auto& [model, dag, cut, mirror, traverser] = t;
  DagManageOptions options;
  options.traversal = DagTraversal::linear;
  for (int frame = 0; frame < 20; ++frame) {
    std::vector<DagOp> ops;
    traverser.manage(options, ops);
  }
  auto [split, holed] = split_sets(cut);
  ASSERT_GT(split.size(), 100u);
  ASSERT_LT(holed.size(), split.size());
  std::reverse(split.begin(), split.end());
  const DagCut rebuilt(dag, split);
  EXPECT_EQ(audit(rebuilt), "ok");
  EXPECT_EQ(rebuilt.triangles(), cut.triangles());
  EXPECT_EQ(rebuilt.fc_size(), cut.fc_size());
  EXPECT_EQ(rebuilt.fs_size(), cut.fs_size());
  for (uint32_t n = 0; n < dag.size(); ++n) ASSERT_EQ(rebuilt.counter(n), cut.counter(n)) << n;
  // Without a node some split node needs, it is no cut.
  EXPECT_THROW(DagCut(dag, holed), Error);
  holed.push_back(dag.size());
  EXPECT_THROW(DagCut(dag, holed), Error);
}

// A route flown as a server does it: each frame loads the compact cut into this thread's dense one,
// traverses, and stores it back. Every frame's operations are those of a traverser that kept its dense cut
// (the code and the cursors are the whole state), the code takes at most 2 bits per split node and one per
// root, and after each store the thread's cut is the base mesh again.
void expect_compact_route(const BuiltModel& model, DagTraversal traversal, DagMode mode, float tolerance) {
  const Dag dag(model.model());
  DagCut kept(dag);
  DagTraverser kept_traverser(kept);
  CompactDagCut compact;
  DagManageOptions options;
  options.traversal = traversal;
  options.mode = mode;
  options.max_ops = 60;
  options.budget = dag.base_faces() + 600;
  for (const Camera& camera : route_of(model)) {
    const ViewCriteria view = make_criteria(test::view_for(model, camera), tolerance);
    kept_traverser.set_view(view);
    for (int frame = 0; frame < 3; ++frame) {
      std::vector<DagOp> expected, ops;
      kept_traverser.manage(options, expected);
      {
        LoadedDagCut loaded(dag, compact);
        ASSERT_EQ(loaded.cut().split_count(), compact.split_count());
        DagTraverser traverser(loaded.cut());
        traverser.set_view(view);
        traverser.manage(options, ops);
        compact = loaded.store();
      }
      ASSERT_EQ(ops.size(), expected.size());
      for (size_t i = 0; i < ops.size(); ++i) {
        ASSERT_EQ(ops[i].node, expected[i].node) << "operation " << i;
        ASSERT_EQ(ops[i].split, expected[i].split) << "operation " << i;
      }
      ASSERT_EQ(compact.split_count(), kept.split_count());
      ASSERT_EQ(compact.triangles(), kept.triangles());
      ASSERT_LE(compact.code_bits(), 2 * uint64_t(kept.split_count()) + dag.roots().size());
      const DagCut dense = compact.dense(dag);
      ASSERT_EQ(audit(dense), "ok");
      ASSERT_EQ(dense.collapse_cursor(), kept.collapse_cursor());
      ASSERT_EQ(dense.split_cursor(), kept.split_cursor());
      for (uint32_t n = 0; n < dag.size(); ++n) ASSERT_EQ(dense.is_split(n), kept.is_split(n)) << n;
    }
  }
  LoadedDagCut base(dag, CompactDagCut{});
  EXPECT_EQ(base.cut().split_count(), 0u);
  EXPECT_EQ(audit(base.cut()), "ok") << "the thread's cut is not the base mesh after the stores";
}

TEST(DagCompact, RoutesAreThoseOfAKeptCutTerrain) {
  for (DagTraversal traversal : {DagTraversal::priority, DagTraversal::linear, DagTraversal::constant_time})
    for (DagMode mode : {DagMode::free, DagMode::budget}) {
      SCOPED_TRACE("traversal " + std::to_string(int(traversal)) + " mode " + std::to_string(int(mode)));
      expect_compact_route(test::built_terrain(), traversal, mode, 1);
      if (::testing::Test::HasFatalFailure()) return;
    }
}
TEST(DagCompact, RoutesAreThoseOfAKeptCutBunny) {
  PMS_REQUIRE_SHARED_MODEL(path, "bunny.ply.xz");
  for (DagTraversal traversal : {DagTraversal::priority, DagTraversal::linear, DagTraversal::constant_time}) {
    SCOPED_TRACE(int(traversal));
    expect_compact_route(*test::built_bunny(), traversal, DagMode::free, 1);
    if (::testing::Test::HasFatalFailure()) return;
  }
}

// A split set that is not a cut is refused and leaves the thread's cut at the base mesh; a second loan of
// the same DAG while the first is alive gets a cut of its own; a loan that ends without store() (an
// exception on the way) still gives the base mesh back.
TEST(DagCompact, LoansAlwaysGiveTheBaseMeshBack) {
  CloseTerrain t;
  auto& [model, dag, cut, mirror, traverser] = t;
  std::vector<DagOp> ops;
  traverser.converge({}, ops);
  auto [split, holed] = split_sets(cut);
  ASSERT_GT(split.size(), 100u);
  ASSERT_LT(holed.size(), split.size());
  EXPECT_THROW(LoadedDagCut(dag, holed), Error);
  holed.push_back(dag.size());
  EXPECT_THROW(LoadedDagCut(dag, holed), Error);
  {
    LoadedDagCut base(dag, CompactDagCut{});
    EXPECT_EQ(base.cut().split_count(), 0u);
    EXPECT_EQ(audit(base.cut()), "ok");
  }
  const CompactDagCut compact(cut);
  {
    LoadedDagCut outer(dag, compact);
    LoadedDagCut inner(dag, compact);
    EXPECT_NE(&outer.cut(), &inner.cut());
    EXPECT_EQ(inner.cut().triangles(), cut.triangles());
    inner.cut().collapse(inner.cut().next_fc(0));
    EXPECT_EQ(outer.cut().triangles(), cut.triangles()) << "the loans share a cut";
    outer.cut().mark(split[0]);  // ends without store(), a mark left
  }
  LoadedDagCut again(dag, CompactDagCut{});
  EXPECT_EQ(again.cut().split_count(), 0u);
  EXPECT_EQ(audit(again.cut()), "ok");
}

}  // namespace
}  // namespace pms
