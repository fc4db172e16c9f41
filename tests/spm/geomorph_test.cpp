// Geomorphs (Hoppe 1997 §5) on their own: after a vsplit the children glide from the parent to their
// places, before an ecol they glide to the parent, the last step lands exactly, and a morph interrupted by
// the opposite operation continues from where the vertex is shown.
#include <gtest/gtest.h>
#include <cmath>

#include "fixtures/view_models.h"
#include "spm/geomorph.h"
#include "spm/hierarchy.h"
#include "spm/selective_mesh.h"
#include "spm/vertex_hierarchy.h"
#include "spm/vertex_id.h"

namespace pms {
namespace {

constexpr uint32_t kFrames = 4;

struct Fixture {
  ModelData view = test::built_sphere().model();
  VertexHierarchy h = test::complete_hierarchy(view);
  SelectiveMesh mesh{h, view.base_faces};
  Geomorphs morphs{kFrames};

  // A root whose split needs no forced chain, split; its children appear.
  uint32_t split_a_root() {
    morphs.sync(mesh);
    for (uint32_t r = 0; r < h.root_count(); ++r) {
      const uint32_t s = h.root_slot(r);
      if (h.is_leaf(s)) continue;
      const size_t before = mesh.vertex_count();
      EXPECT_TRUE(mesh.vsplit(s).done);
      if (mesh.vertex_count() != before + 1) continue;  // a chain came along; try another root
      const uint32_t t = h.first_child(s);
      morphs.appear(h, t);
      morphs.appear(h, t + 1);
      return s;
    }
    ADD_FAILURE() << "no root splits alone";
    return kNone;
  }
};

void expect_at(const float* shown, const float* expected, float tolerance = 0) {
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(shown[k], expected[k], tolerance) << "coordinate " << k;
}

void expect_exactly(const float* shown, const float* expected) {
  for (int k = 0; k < 3; ++k) EXPECT_EQ(shown[k], expected[k]) << "coordinate " << k;
}

TEST(Geomorph, SplitChildrenGlideFromTheParent) {
  Fixture f;
  const uint32_t s = f.split_a_root();
  ASSERT_NE(s, kNone);
  const uint32_t t = f.h.first_child(s), u = t + 1;
  const float* ps = f.h.position(s);
  const float* pt = f.h.position(t);
  ASSERT_FALSE(ps[0] == pt[0] && ps[1] == pt[1] && ps[2] == pt[2]);
  expect_exactly(f.morphs.shown(f.h, t), ps);  // before the first step: where v_s was
  expect_exactly(f.morphs.shown(f.h, u), ps);  // v_u sits where v_s sat: it never moves
  for (uint32_t step = 1; step <= kFrames; ++step) {
    f.morphs.advance(f.mesh);
    const float w = float(step) / kFrames;
    const float expected[3] = {ps[0] + (pt[0] - ps[0]) * w, ps[1] + (pt[1] - ps[1]) * w, ps[2] + (pt[2] - ps[2]) * w};
    expect_at(f.morphs.shown(f.h, t), expected, 1e-6f);
  }
  expect_exactly(f.morphs.shown(f.h, t), pt);  // lands exactly
  EXPECT_EQ(f.morphs.morphing(), 0u);
  MeshArrays arrays;
  f.mesh.extract(arrays);
  f.morphs.apply(f.h, arrays);
  for (size_t i = 0; i < arrays.slots.size(); ++i)
    expect_exactly(&arrays.positions[3 * i], f.h.position(arrays.slots[i]));
}

TEST(Geomorph, CollapseWaitsUntilTheChildrenArrive) {
  Fixture f;
  const uint32_t s = f.split_a_root();
  ASSERT_NE(s, kNone);
  const uint32_t t = f.h.first_child(s);
  for (uint32_t i = 0; i < kFrames; ++i) f.morphs.advance(f.mesh);
  f.morphs.begin_collapse(f.h, s);
  for (uint32_t step = 1; step <= kFrames; ++step) {
    EXPECT_FALSE(f.morphs.collapse_ready(f.h, s)) << "step " << step;
    f.morphs.advance(f.mesh);
    f.morphs.begin_collapse(f.h, s);  // asked again each frame: does not restart
  }
  EXPECT_TRUE(f.morphs.collapse_ready(f.h, s));
  expect_exactly(f.morphs.shown(f.h, t), f.h.position(s));
  expect_exactly(f.morphs.shown(f.h, t + 1), f.h.position(s));
  ASSERT_TRUE(f.mesh.ecol(s));
  f.morphs.collapsed(f.h, s);
  EXPECT_EQ(f.morphs.morphing(), 0u);
  expect_exactly(f.morphs.shown(f.h, s), f.h.position(s));
  // Split again: the children start from the parent again, not from where they were left.
  ASSERT_TRUE(f.mesh.vsplit(s).done);
  f.morphs.appear(f.h, t);
  expect_exactly(f.morphs.shown(f.h, t), f.h.position(s));
}

TEST(Geomorph, InterruptedMorphsContinueFromWhereTheyAre) {
  Fixture f;
  const uint32_t s = f.split_a_root();
  ASSERT_NE(s, kNone);
  const uint32_t t = f.h.first_child(s);
  const float* ps = f.h.position(s);
  const float* pt = f.h.position(t);
  // Split-in interrupted halfway by a collapse: from the halfway point to the parent.
  f.morphs.advance(f.mesh);
  f.morphs.advance(f.mesh);
  const float half[3] = {f.morphs.shown(f.h, t)[0], f.morphs.shown(f.h, t)[1], f.morphs.shown(f.h, t)[2]};
  f.morphs.begin_collapse(f.h, s);
  EXPECT_TRUE(f.morphs.collapsing(t));
  f.morphs.advance(f.mesh);
  const float quarter[3] = {half[0] + (ps[0] - half[0]) / kFrames, half[1] + (ps[1] - half[1]) / kFrames,
                            half[2] + (ps[2] - half[2]) / kFrames};
  expect_at(f.morphs.shown(f.h, t), quarter, 1e-6f);
  // ... and that collapse called off: back to its own place, from where it is, landing exactly.
  const float at[3] = {f.morphs.shown(f.h, t)[0], f.morphs.shown(f.h, t)[1], f.morphs.shown(f.h, t)[2]};
  f.morphs.cancel_collapse(f.h, t);
  f.morphs.cancel_collapse(f.h, t + 1);
  EXPECT_FALSE(f.morphs.collapsing(t));
  EXPECT_FALSE(f.morphs.collapse_ready(f.h, s));
  f.morphs.advance(f.mesh);
  const float back[3] = {at[0] + (pt[0] - at[0]) / kFrames, at[1] + (pt[1] - at[1]) / kFrames,
                         at[2] + (pt[2] - at[2]) / kFrames};
  expect_at(f.morphs.shown(f.h, t), back, 1e-6f);
  for (uint32_t i = 1; i < kFrames; ++i) f.morphs.advance(f.mesh);
  expect_exactly(f.morphs.shown(f.h, t), pt);
  EXPECT_EQ(f.morphs.morphing(), 0u);
}

// A vertex split while it is still moving: its children start where it is shown, and its own morph stops.
TEST(Geomorph, SplitWhileMovingStartsFromTheShownPlace) {
  Fixture f;
  const uint32_t s = f.split_a_root();
  ASSERT_NE(s, kNone);
  f.morphs.advance(f.mesh);
  // Find a moving child that splits alone.
  for (uint32_t c : {f.h.first_child(s), f.h.first_child(s) + 1}) {
    if (f.h.is_leaf(c)) continue;
    const float shown[3] = {f.morphs.shown(f.h, c)[0], f.morphs.shown(f.h, c)[1], f.morphs.shown(f.h, c)[2]};
    const size_t before = f.mesh.vertex_count();
    ASSERT_TRUE(f.mesh.vsplit(c).done);
    if (f.mesh.vertex_count() != before + 1) continue;
    const uint32_t g = f.h.first_child(c);
    f.morphs.appear(f.h, g);
    f.morphs.appear(f.h, g + 1);
    expect_exactly(f.morphs.shown(f.h, g), shown);
    expect_exactly(f.morphs.shown(f.h, g + 1), shown);
    for (uint32_t i = 0; i < kFrames; ++i) f.morphs.advance(f.mesh);
    expect_exactly(f.morphs.shown(f.h, g), f.h.position(g));
    expect_exactly(f.morphs.shown(f.h, g + 1), f.h.position(g + 1));  // = v_s's place, reached from the shown one
    expect_exactly(f.morphs.shown(f.h, c), shown);                    // frozen where its children came from
    return;
  }
  GTEST_SKIP() << "no child of the split root splits alone";
}

TEST(Geomorph, TurningOffLandsEverything) {
  Fixture f;
  const uint32_t s = f.split_a_root();
  ASSERT_NE(s, kNone);
  f.morphs.advance(f.mesh);
  EXPECT_GT(f.morphs.morphing(), 0u);
  f.morphs.set_frames(0);
  EXPECT_EQ(f.morphs.morphing(), 0u);
  MeshArrays arrays;
  f.mesh.extract(arrays);
  f.morphs.apply(f.h, arrays);
  for (size_t i = 0; i < arrays.slots.size(); ++i)
    expect_exactly(&arrays.positions[3 * i], f.h.position(arrays.slots[i]));
}

}  // namespace
}  // namespace pms
