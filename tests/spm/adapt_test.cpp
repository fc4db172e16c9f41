// The adaptation loop (Hoppe 1997 §5; kim-lee-kobbelt 2005 §5.3) on built models: it reaches the least
// fixed point of the view (the naive split-only closure), whatever the order packets arrive in and
// whatever the op cap (property 3, docs/architecture.md), comes back from a close view to the far view's mesh,
// keeps every visible input face at τ = 0, and stays a manifold through a path with geomorphs.
#include <gtest/gtest.h>
#include <algorithm>
#include <cmath>
#include <random>

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

std::string invariants(const SelectiveMesh& mesh) {
  std::string why;
  return mesh.check_invariants(&why) ? "ok" : why;
}

struct NamedView {
  std::string name;
  Camera camera;
};

std::vector<NamedView> views_of(const BuiltModel& model) {
  std::vector<NamedView> views;
  views.push_back({"far", test::framing_camera(model, {0.3f, 0.2f, 1}, 4)});
  views.push_back({"whole", test::framing_camera(model, {1, 0.5f, 0.4f}, 1)});
  views.push_back({"close", test::framing_camera(model, {-0.4f, 0.3f, 1}, 0.35f)});
  views.push_back({"grazing", test::framing_camera(model, {1, 0.05f, -0.2f}, 0.6f, 30)});
  if (model.up_axis == 2) {
    views.push_back({"above", test::framing_camera(model, {0.1f, 0.2f, 1}, 0.8f)});
    views.push_back({"low", test::framing_camera(model, {1, 0.3f, 0.08f}, 0.45f, 60)});
  }
  return views;
}

// Converges from the base mesh over `hierarchy` (complete or empty), fetching what the loop reports.
std::vector<IdFace> converge_with(const BuiltModel& model, VertexHierarchy& hierarchy, const ViewParams& view,
                                  const AdaptOptions& options, const SelectiveRefinement::Fetch& fetch,
                                  ConvergeStats* stats = nullptr) {
  SelectiveMesh mesh(hierarchy, model.model().base_faces);
  SelectiveRefinement refinement(mesh, model.h.scale, options);
  refinement.set_view(view);
  const ConvergeStats s = refinement.converge(fetch);
  if (stats) *stats = s;
  EXPECT_EQ(invariants(mesh), "ok");
  return test::id_faces(mesh);
}

// Packets arrive in a random order: of what the loop reports missing a random part is delivered per frame,
// together with packets nobody asked for yet (a server sending ahead). Checks what the loop reports.
SelectiveRefinement::Fetch random_arrivals(VertexHierarchy& hierarchy, const ModelData& model, std::mt19937& rng,
                                           const SelectiveMesh& mesh) {
  return [&hierarchy, &model, &rng, &mesh](std::span<const uint32_t> missing) -> size_t {
    std::vector<uint32_t> ask(missing.begin(), missing.end());
    for (uint32_t v : ask) {
      EXPECT_TRUE(mesh.is_active(v) && hierarchy.is_leaf(v)) << "reported a vertex that is not an active leaf";
    }
    std::shuffle(ask.begin(), ask.end(), rng);
    ask.resize(1 + std::uniform_int_distribution<size_t>(0, ask.size() - 1)(rng));
    // Unsolicited: a few random known leaves that are internal in the model.
    for (int extra = std::uniform_int_distribution<int>(0, 3)(rng); extra > 0; --extra)
      ask.push_back(std::uniform_int_distribution<uint32_t>(0, hierarchy.size() - 1)(rng));
    return add_model_splits(hierarchy, model, ask);
  };
}

void expect_order_and_cap_independence(const BuiltModel& model, const std::vector<uint32_t>& caps, int seeds) {
  const ModelData m = model.model();
  size_t views_checked = 0;
  for (const NamedView& named : views_of(model)) {
    const ViewParams view = test::view_for(model, named.camera);
    for (float tau : {0.5f, 2.0f}) {
      const std::string where = model.name + " " + named.name + " tau " + std::to_string(tau);
      SCOPED_TRACE(where);
      const std::vector<IdFace> target = test::naive_refinement(model, view, tau);
      AdaptOptions options;
      options.tolerance = tau;

      VertexHierarchy complete = test::complete_hierarchy(m);
      ConvergeStats stats;
      ASSERT_EQ(converge_with(model, complete, view, options, {}, &stats), target) << "complete hierarchy";
      EXPECT_LE(stats.frames, 3u) << "all packets known: one frame does it, one confirms";

      VertexHierarchy on_demand = VertexHierarchy::from_model(m);
      const auto fetch = [&](std::span<const uint32_t> leaves) { return add_model_splits(on_demand, m, leaves); };
      ASSERT_EQ(converge_with(model, on_demand, view, options, fetch), target) << "packets on demand";

      for (int seed = 1; seed <= seeds; ++seed) {
        std::mt19937 rng(seed);
        VertexHierarchy partial = VertexHierarchy::from_model(m);
        SelectiveMesh mesh(partial, m.base_faces);
        SelectiveRefinement refinement(mesh, m.scale, options);
        refinement.set_view(view);
        refinement.converge(random_arrivals(partial, m, rng, mesh));
        ASSERT_EQ(invariants(mesh), "ok");
        ASSERT_EQ(test::id_faces(mesh), target) << "random arrivals, seed " << seed;
      }
      for (uint32_t cap : caps) {
        options.max_ops = cap;
        VertexHierarchy h = test::complete_hierarchy(m);
        ASSERT_EQ(converge_with(model, h, view, options, {}), target) << "cap " << cap;
      }
      ++views_checked;
    }
  }
  EXPECT_GT(views_checked, 0u);
}

TEST(Adapt, OrderAndCapIndependenceSphere) { expect_order_and_cap_independence(test::built_sphere(), {1, 7, 100}, 3); }
TEST(Adapt, OrderAndCapIndependenceTerrain) { expect_order_and_cap_independence(test::built_terrain(), {5, 64}, 3); }
TEST(Adapt, OrderAndCapIndependenceBunny) {
  PMS_REQUIRE_SHARED_MODEL(path, "bunny.ply.xz");
  expect_order_and_cap_independence(*test::built_bunny(), {200}, 2);
}

// The views do refine (else the tests above prove little): a far view coarse, a close one fine.
TEST(Adapt, ViewsRefineAsExpected) {
  const BuiltModel& model = test::built_terrain();
  size_t previous = 0;
  for (float distance : {8.0f, 2.0f, 0.5f}) {
    const ViewParams view = test::view_for(model, test::framing_camera(model, {0.3f, 0.2f, 1}, distance));
    const size_t faces = test::naive_refinement(model, view, 1).size();
    EXPECT_GT(faces, previous) << "distance " << distance;
    previous = faces;
  }
  EXPECT_GT(previous, model.h.base_faces.size() / 3 * 10);
  EXPECT_LT(previous, model.input.face_count());
}

// Far after close: the loop collapses back to exactly the far view's own target, and the other way round.
void expect_history_independence(const BuiltModel& model) {
  const ModelData m = model.model();
  const std::vector<NamedView> views = views_of(model);
  for (size_t a = 0; a < views.size(); ++a) {
    for (size_t b = 0; b < views.size(); ++b) {
      if (a == b) continue;
      SCOPED_TRACE(model.name + " " + views[a].name + " then " + views[b].name);
      const VertexHierarchy h = test::complete_hierarchy(m);
      SelectiveMesh mesh(h, m.base_faces);
      SelectiveRefinement refinement(mesh, m.scale);
      refinement.set_view(test::view_for(model, views[a].camera));
      refinement.converge();
      refinement.set_view(test::view_for(model, views[b].camera));
      const ConvergeStats back = refinement.converge();
      ASSERT_EQ(invariants(mesh), "ok");
      ASSERT_EQ(test::id_faces(mesh), test::naive_refinement(model, test::view_for(model, views[b].camera), 1));
      if (views[a].name == "close" && views[b].name == "far") {
        EXPECT_GT(back.ecols, 0u);
      }
    }
  }
}

TEST(Adapt, FarAfterCloseEqualsFarSphere) { expect_history_independence(test::built_sphere()); }
TEST(Adapt, FarAfterCloseEqualsFarTerrain) { expect_history_independence(test::built_terrain()); }
TEST(Adapt, FarAfterCloseEqualsFarBunny) {
  PMS_REQUIRE_SHARED_MODEL(path, "bunny.ply.xz");
  expect_history_independence(*test::built_bunny());
}

// A display's frames, one adapt() each, under a time budget small enough to cap every frame and with
// geomorphs: at_rest() says when the frames are done, and the mesh is then the view's target, far after
// close too (a frame's collapses leave parents that only the next walk finds unwanted).
// A complete model's mesh adapted frame by frame under a time budget small enough to cap every frame, with
// geomorphs.
struct BudgetedFrames {
  explicit BudgetedFrames(const ModelData& m)
      : h(test::complete_hierarchy(m)), mesh(h, m.base_faces), refinement(mesh, m.scale, options()) {}
  static AdaptOptions options() {
    AdaptOptions options;
    options.time_budget_us = 1;
    options.morph_frames = 3;
    return options;
  }
  const VertexHierarchy h;
  SelectiveMesh mesh;
  SelectiveRefinement refinement;
};

void expect_frames_until_at_rest_reach_the_target(const BuiltModel& model) {
  std::vector<NamedView> views = views_of(model);
  views.push_back(views.front());  // far again, after close
  BudgetedFrames frames_of(model.model());
  SelectiveMesh& mesh = frames_of.mesh;
  SelectiveRefinement& refinement = frames_of.refinement;
  EXPECT_TRUE(refinement.at_rest()) << "no frame yet";
  for (const NamedView& named : views) {
    SCOPED_TRACE(model.name + " " + named.name);
    const ViewParams view = test::view_for(model, named.camera);
    refinement.set_view(view);
    uint32_t frames = 0, capped = 0;
    do {
      const FrameStats stats = refinement.adapt();
      capped += stats.capped;
      if (stats.ops() > 0) {
        EXPECT_FALSE(refinement.at_rest()) << "a frame that operated";
      }
    } while (!refinement.at_rest() && ++frames < 100000);
    ASSERT_TRUE(refinement.at_rest());
    EXPECT_EQ(refinement.geomorphs().morphing(), 0u);
    ASSERT_EQ(invariants(mesh), "ok");
    EXPECT_EQ(test::id_faces(mesh), test::naive_refinement(model, view, 1));
    if (named.name == "close") {
      EXPECT_GT(capped, 0u) << "the budget never capped a frame: the test proves nothing";
    }
  }
}

TEST(Adapt, FramesUntilAtRestReachTheTargetSphere) { expect_frames_until_at_rest_reach_the_target(test::built_sphere()); }
TEST(Adapt, FramesUntilAtRestReachTheTargetTerrain) {
  expect_frames_until_at_rest_reach_the_target(test::built_terrain());
}

// A moving view under a time budget that pauses every walk after one tree (Hoppe's amortized traversal):
// every frame leaves a valid mesh, a tree not walked for frames keeps what it forced in the others (or a
// view that barely moves would split and collapse the same nodes round after round), and once the view
// stays the frames settle on its target.
void expect_paused_walks_settle_on_the_target(const BuiltModel& model) {
  const std::vector<NamedView> views = views_of(model);
  BudgetedFrames frames_of(model.model());
  SelectiveMesh& mesh = frames_of.mesh;
  SelectiveRefinement& refinement = frames_of.refinement;
  constexpr int kSteps = 12;
  uint32_t paused = 0;
  for (size_t i = 0; i + 1 < views.size(); ++i) {
    SCOPED_TRACE(model.name + " " + views[i].name + " to " + views[i + 1].name);
    const Camera& from = views[i].camera;
    const Camera& to = views[i + 1].camera;
    for (int step = 0; step <= kSteps; ++step) {
      Camera camera = from;
      const float t = float(step) / kSteps;
      for (int k = 0; k < 3; ++k) {
        camera.eye[k] = from.eye[k] + t * (to.eye[k] - from.eye[k]);
        camera.target[k] = from.target[k] + t * (to.target[k] - from.target[k]);
      }
      camera.fovy_deg = from.fovy_deg + t * (to.fovy_deg - from.fovy_deg);
      refinement.set_view(test::view_for(model, camera));
      const FrameStats stats = refinement.adapt();
      paused += stats.capped && stats.ops() < kMinOpsPerBudgetedFrame;
      ASSERT_EQ(invariants(mesh), "ok");
    }
    // The view barely moves: every tree's walk finds what it found a round before, so the operations stop.
    Camera still = to;
    uint32_t late_ops = 0;
    for (int frame = 0; frame < 4000; ++frame) {
      still.eye[0] = to.eye[0] * (1 + (frame % 2 ? 1e-7f : -1e-7f));
      refinement.set_view(test::view_for(model, still));
      const FrameStats stats = refinement.adapt();
      if (frame >= 3000) late_ops += stats.ops();
    }
    EXPECT_EQ(late_ops, 0u) << "the same nodes split and collapsed round after round";
    const ViewParams view = test::view_for(model, to);
    refinement.set_view(view);
    uint32_t frames = 0;
    while (!refinement.at_rest() && ++frames < 100000) refinement.adapt();
    ASSERT_TRUE(refinement.at_rest());
    ASSERT_EQ(invariants(mesh), "ok");
    EXPECT_EQ(test::id_faces(mesh), test::naive_refinement(model, view, 1));
  }
  EXPECT_GT(paused, 0u) << "no walk paused: the test proves nothing";
}

TEST(Adapt, PausedWalksSettleOnTheTargetSphere) { expect_paused_walks_settle_on_the_target(test::built_sphere()); }
TEST(Adapt, PausedWalksSettleOnTheTargetTerrain) { expect_paused_walks_settle_on_the_target(test::built_terrain()); }

// A fresh mesh and refinement reach a view's target in one frame from the base, and so does a mesh whose
// state was used before (fully refined, then coarsened back): per-slot state made on first use
// (SelectiveMesh records, the loop's decoded slots) must not differ from state left behind.
void expect_fresh_equals_reused(const BuiltModel& model) {
  const ModelData m = model.model();
  const VertexHierarchy h = test::complete_hierarchy(m);
  SelectiveMesh reused(h, m.base_faces);
  for (uint32_t node : m.split_order) reused.vsplit(h.find(m.id(node)));
  SelectiveRefinement reused_loop(reused, m.scale);
  for (const NamedView& named : views_of(model)) {
    SCOPED_TRACE(model.name + " " + named.name);
    const ViewParams view = test::view_for(model, named.camera);
    const std::vector<IdFace> target = test::naive_refinement(model, view, 1);
    reused_loop.set_view(view);
    reused_loop.set_options(AdaptOptions{1e9f, 0, 0});  // nothing is visible at that tolerance: back to the base
    reused_loop.converge();
    ASSERT_EQ(reused.face_count(), m.base_faces.size() / 3);
    reused_loop.set_options(AdaptOptions{1, 0, 0});
    reused_loop.adapt();
    EXPECT_EQ(reused_loop.adapt().ops(), 0u) << "from the base in one frame";
    ASSERT_EQ(invariants(reused), "ok");
    EXPECT_EQ(test::id_faces(reused), target);

    SelectiveMesh fresh(h, m.base_faces);
    SelectiveRefinement fresh_loop(fresh, m.scale);
    fresh_loop.set_view(view);
    fresh_loop.adapt();
    EXPECT_EQ(fresh_loop.adapt().ops(), 0u) << "from the base in one frame";
    ASSERT_EQ(invariants(fresh), "ok");
    EXPECT_EQ(test::id_faces(fresh), target);
  }
}

TEST(Adapt, FreshAndReusedMeshesAgreeSphere) { expect_fresh_equals_reused(test::built_sphere()); }
TEST(Adapt, FreshAndReusedMeshesAgreeTerrain) { expect_fresh_equals_reused(test::built_terrain()); }
TEST(Adapt, FreshAndReusedMeshesAgreeBunny) {
  PMS_REQUIRE_SHARED_MODEL(path, "bunny.ply.xz");
  expect_fresh_equals_reused(*test::built_bunny());
}

// A frame after a converged one with nothing changed returns without walking; a split made behind the
// loop's back, a new view or new options make the next frame walk again and reach the target.
TEST(Adapt, SteadyFramesSkipOnlyWhileNothingChanged) {
  const BuiltModel& model = test::built_terrain();
  const ModelData m = model.model();
  const VertexHierarchy h = test::complete_hierarchy(m);
  const ViewParams view = test::view_for(model, test::framing_camera(model, {0.3f, 0.2f, 1}, 2));
  const std::vector<IdFace> target = test::naive_refinement(model, view, 1);
  SelectiveMesh mesh(h, m.base_faces);
  SelectiveRefinement refinement(mesh, m.scale);
  refinement.set_view(view);
  refinement.converge();
  const FrameStats steady = refinement.adapt();
  EXPECT_EQ(steady.evaluated, 0u);
  EXPECT_EQ(steady.ops(), 0u);
  ASSERT_EQ(test::id_faces(mesh), target);

  uint32_t extra = kNone;  // an active vertex the target does not split
  for (uint32_t v : mesh.active_vertices()) {
    if (!h.is_leaf(v)) extra = v;
  }
  ASSERT_NE(extra, kNone);
  ASSERT_TRUE(mesh.vsplit(extra).done);
  const FrameStats after_split = refinement.adapt();
  EXPECT_GT(after_split.evaluated, 0u);
  EXPECT_GT(after_split.ecols, 0u);
  EXPECT_EQ(test::id_faces(mesh), target);

  EXPECT_EQ(refinement.adapt().ops(), 0u) << "the target was reached";
  refinement.set_view(view);
  EXPECT_EQ(refinement.adapt().evaluated, 0u) << "the same view again changes nothing";
  refinement.rewalk();
  const FrameStats walked = refinement.adapt();
  EXPECT_GT(walked.evaluated, 0u);
  EXPECT_EQ(walked.ops(), 0u);
  refinement.rewalk();
  EXPECT_EQ(refinement.adapt().evaluated, walked.evaluated) << "a walk over the same mesh evaluates the same nodes";
  refinement.set_options(AdaptOptions{1e9f, 0, 0});
  EXPECT_GT(refinement.adapt().ecols, 0u) << "new options walk again";
  refinement.set_options(AdaptOptions{1, 0, 0});
  refinement.converge();
  refinement.set_view(test::view_for(model, test::framing_camera(model, {0.3f, 0.2f, 1}, 8)));
  EXPECT_GT(refinement.adapt().evaluated, 0u) << "a new view walks again";
}

// τ = 0 with the whole model in view: every input face that is inside the frustum and front-facing is a
// face of the refined mesh (culling is conservative, and nothing with an error is left coarse).
void expect_visible_faces_kept(const BuiltModel& model, const Camera& camera) {
  const ViewParams view = test::view_for(model, camera);
  const ModelData m = model.model();
  VertexHierarchy h = test::complete_hierarchy(m);
  SelectiveMesh mesh(h, m.base_faces);
  SelectiveRefinement refinement(mesh, m.scale, AdaptOptions{0, 0, 0});
  refinement.set_view(view);
  refinement.converge();
  const auto kept = test::leaf_input_faces(mesh, model);
  const float* p = model.input.positions.data();
  size_t visible = 0;
  for (size_t i = 0; i < model.input.indices.size(); i += 3) {
    const uint32_t* f = &model.input.indices[i];
    const float* a = p + 3 * f[0];
    const float* b = p + 3 * f[1];
    const float* c = p + 3 * f[2];
    float n[3], e[3];
    const float ab[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, ac[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    n[0] = ab[1] * ac[2] - ab[2] * ac[1];
    n[1] = ab[2] * ac[0] - ab[0] * ac[2];
    n[2] = ab[0] * ac[1] - ab[1] * ac[0];
    for (int k = 0; k < 3; ++k) e[k] = view.eye[k] - a[k];
    const float nl = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]),
                el = std::sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
    if (!(n[0] * e[0] + n[1] * e[1] + n[2] * e[2] > 1e-3f * nl * el)) continue;  // back-facing or edge-on
    bool inside = true;
    for (const float* corner : {a, b, c})
      for (const float* plane : view.planes)
        inside &= plane[0] * corner[0] + plane[1] * corner[1] + plane[2] * corner[2] + plane[3] > 0;
    if (!inside) continue;
    ++visible;
    std::array<uint32_t, 3> face{f[0], f[1], f[2]};
    std::rotate(face.begin(), std::min_element(face.begin(), face.end()), face.end());
    ASSERT_TRUE(std::binary_search(kept.begin(), kept.end(), face))
        << model.name << ": visible input face " << i / 3 << " missing";
  }
  EXPECT_GT(visible, model.input.face_count() / 4) << model.name;
  EXPECT_LT(mesh.face_count(), model.input.face_count()) << model.name << ": back faces should stay coarse";
}

TEST(Adapt, ZeroToleranceKeepsEveryVisibleFaceSphere) {
  expect_visible_faces_kept(test::built_sphere(), test::framing_camera(test::built_sphere(), {0.2f, 0.3f, 1}, 1));
}
TEST(Adapt, ZeroToleranceKeepsEveryVisibleFaceBunny) {
  PMS_REQUIRE_SHARED_MODEL(path, "bunny.ply.xz");
  const BuiltModel& bunny = *test::built_bunny();
  expect_visible_faces_kept(bunny, test::framing_camera(bunny, {0.1f, 0.2f, 1}, 1.1f));
  expect_visible_faces_kept(bunny, test::framing_camera(bunny, {-1, 0.1f, -0.3f}, 0.5f));  // partly out of view
}

// Terrain seen from high above with a narrow lens: every face is in view and faces the eye, so τ = 0
// gives back the whole input.
TEST(Adapt, ZeroToleranceFromAboveGivesTheFullTerrain) {
  const BuiltModel& model = test::built_terrain();
  const test::RefinedFromAbove refined(model);
  EXPECT_EQ(refined.mesh.vertex_count(), model.input.vertex_count());
  EXPECT_EQ(test::leaf_input_faces(refined.mesh, model), test::canonical_input_faces(model.input));
}

// A chain of forced splits that stops at an unknown packet reports that leaf; what the chain already
// split stays (no split/collapse churn from one frame to the next while waiting).
TEST(Adapt, BlockedChainsReportTheirLeafAndHold) {
  const BuiltModel& model = test::built_terrain();
  const ModelData m = model.model();
  const ViewParams view = test::view_for(model, test::framing_camera(model, {1, 0.3f, 0.1f}, 0.45f, 60));
  size_t chain_reports = 0, frames_waiting = 0;
  for (uint32_t seed = 1; seed <= 4; ++seed) {
    std::mt19937 rng(seed);
    VertexHierarchy h = VertexHierarchy::from_model(m);
    SelectiveMesh mesh(h, m.base_faces);
    SelectiveRefinement refinement(mesh, m.scale);
    refinement.set_view(view);
    for (int frame = 0; frame < 400; ++frame) {
      const FrameStats stats = refinement.adapt();
      if (stats.missing == 0 && stats.ops() == 0) break;
      std::vector<uint32_t> wanted;
      for (uint32_t v : refinement.missing()) {
        ASSERT_TRUE(mesh.is_active(v) && h.is_leaf(v));
        if (!refinement.qrefine(v)) ++chain_reports;  // asked for only because a chain needs it
      }
      // Withhold packets for a frame now and then: the mesh must hold still meanwhile.
      if (frame % 3 == 2) {
        ++frames_waiting;
        const std::vector<IdFace> before = test::id_faces(mesh);
        const FrameStats idle = refinement.adapt();
        EXPECT_EQ(idle.ops(), 0u) << "frame " << frame << " seed " << seed;
        EXPECT_EQ(test::id_faces(mesh), before);
      }
      std::vector<uint32_t> ask(refinement.missing().begin(), refinement.missing().end());
      std::shuffle(ask.begin(), ask.end(), rng);
      ask.resize((ask.size() + 1) / 2);
      add_model_splits(h, m, ask);
    }
    ASSERT_EQ(invariants(mesh), "ok");
    EXPECT_EQ(test::id_faces(mesh), test::naive_refinement(model, view, 1));
  }
  EXPECT_GT(chain_reports, 0u) << "no forced chain ever waited for a packet: that path went untested";
  EXPECT_GT(frames_waiting, 0u);
}

// A camera path with geomorphs: the mesh is a valid manifold every frame, morphing vertices are shown
// between where they come from and where they go, and once the camera stops everything lands.
TEST(Adapt, PathWithGeomorphsStaysManifold) {
  const BuiltModel* bunny = test::built_bunny();
  const BuiltModel& model = bunny ? *bunny : test::built_terrain();
  const ModelData m = model.model();
  VertexHierarchy h = VertexHierarchy::from_model(m);
  SelectiveMesh mesh(h, m.base_faces);
  AdaptOptions options;
  options.morph_frames = kDefaultMorphFrames;
  options.max_ops = 3000;
  SelectiveRefinement refinement(mesh, m.scale, options);
  constexpr int kFrames = 90;
  size_t morphed = 0, ecols = 0, vsplits = 0;
  MeshArrays arrays;
  Camera camera;
  for (int frame = 0; frame < kFrames; ++frame) {
    const float t = float(frame) / kFrames, angle = 6.2831853f * t;
    // Orbit while zooming in and out.
    const float distance = 0.4f + 1.2f * (0.5f + 0.5f * std::cos(2 * angle));
    const std::array<float, 3> dir = model.up_axis == 2 ? std::array<float, 3>{std::cos(angle), std::sin(angle), 0.4f}
                                                        : std::array<float, 3>{std::cos(angle), 0.3f, std::sin(angle)};
    camera = test::framing_camera(model, dir, distance);
    refinement.set_view(test::view_for(model, camera));
    const FrameStats stats = refinement.adapt();
    add_model_splits(h, m, refinement.missing());
    morphed += stats.morphing;
    ecols += stats.ecols;
    vsplits += stats.vsplits;
    if (frame % 10 == 0 || frame == kFrames - 1) {
      ASSERT_EQ(invariants(mesh), "ok") << "frame " << frame;
    }
    refinement.extract(arrays);
    ASSERT_EQ(arrays.positions.size(), 3 * mesh.vertex_count());
    for (float x : arrays.positions) ASSERT_TRUE(std::isfinite(x));
  }
  EXPECT_GT(morphed, 0u);
  EXPECT_GT(ecols, 0u);
  EXPECT_GT(vsplits, 0u);
  // The camera stops: everything lands and the mesh is the view's target.
  options.max_ops = 0;
  refinement.set_options(options);
  refinement.converge([&](std::span<const uint32_t> leaves) { return add_model_splits(h, m, leaves); });
  EXPECT_EQ(refinement.geomorphs().morphing(), 0u);
  EXPECT_EQ(test::id_faces(mesh), test::naive_refinement(model, test::view_for(model, camera), 1));
  refinement.extract(arrays);
  for (size_t i = 0; i < arrays.slots.size(); ++i)
    for (int k = 0; k < 3; ++k) ASSERT_EQ(arrays.positions[3 * i + k], h.position(arrays.slots[i])[k]);
}

// With geomorphs a collapse waits until the children have reached the parent; the end result is the same.
TEST(Adapt, GeomorphsDelayCollapsesAndEndTheSame) {
  const BuiltModel& model = test::built_terrain();
  const ModelData m = model.model();
  const Camera close = test::framing_camera(model, {-0.4f, 0.3f, 1}, 0.35f);
  const Camera far = test::framing_camera(model, {0.3f, 0.2f, 1}, 4);
  const VertexHierarchy h = test::complete_hierarchy(m);
  SelectiveMesh mesh(h, m.base_faces);
  AdaptOptions options;
  options.morph_frames = 4;
  SelectiveRefinement refinement(mesh, m.scale, options);
  refinement.set_view(test::view_for(model, close));
  const FrameStats first = refinement.adapt();
  EXPECT_GT(first.vsplits, 0u);
  EXPECT_GT(first.morphing, 0u);
  refinement.converge();
  EXPECT_EQ(refinement.geomorphs().morphing(), 0u);
  refinement.set_view(test::view_for(model, far));
  for (uint32_t frame = 0; frame < options.morph_frames; ++frame) {
    const FrameStats stats = refinement.adapt();
    EXPECT_EQ(stats.ecols, 0u) << "frame " << frame << ": collapsed before the children arrived";
    EXPECT_GT(stats.morphing, 0u);
  }
  EXPECT_GT(refinement.adapt().ecols, 0u);
  refinement.converge();
  EXPECT_EQ(invariants(mesh), "ok");
  EXPECT_EQ(test::id_faces(mesh), test::naive_refinement(model, test::view_for(model, far), 1));
}

}  // namespace
}  // namespace pms
