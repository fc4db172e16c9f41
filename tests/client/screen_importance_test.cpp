// cheng-ooi 2008 §4.2's client importance (client/screen_importance.h): the front ranked by the pixels of
// each vertex's incident faces in the renderer's face-id buffer.
#include <gtest/gtest.h>
#include <algorithm>
#include <set>
#include <span>

#include "builder/build.h"
#include "client/face_id_importance.h"
#include "client/screen_importance.h"
#include "common/camera.h"
#include "common/error.h"
#include "io/shapes.h"
#include "spm/adapt.h"
#include "spm/hierarchy.h"
#include "spm/selective_mesh.h"
#include "spm/vertex_hierarchy.h"

namespace pms {
namespace {

// A model's base mesh as a client holds it, refined for `camera` at τ (0 = the base mesh as it is).
struct ClientMesh {
  Hierarchy built;
  ModelData model;
  VertexHierarchy hierarchy;
  std::unique_ptr<SelectiveMesh> mesh;

  ClientMesh(const Mesh& input, const Camera& camera, float tolerance)
      : built(build_progressive_mesh(input, BuildOptions{}).hierarchy),
        model(model_of(built)),
        hierarchy(VertexHierarchy::from_model(model)),
        mesh(std::make_unique<SelectiveMesh>(hierarchy, model.base_faces)) {
    if (tolerance <= 0) return;
    SelectiveRefinement refinement(*mesh, model.scale, AdaptOptions{tolerance, 0, 0});
    refinement.set_view(view(camera));
    refinement.converge([&](std::span<const uint32_t> leaves) { return add_model_splits(hierarchy, model, leaves); });
  }
  ViewParams view(const Camera& camera) const { return make_view(camera, model.bbox_min, model.bbox_max); }
};

Camera looking_at(float ex, float ey, float ez, float tx, float ty, float tz) {
  Camera c;
  c.eye[0] = ex, c.eye[1] = ey, c.eye[2] = ez;
  c.target[0] = tx, c.target[1] = ty, c.target[2] = tz;
  c.width = 160;
  c.height = 120;
  return c;
}

uint64_t pixels_with_a_face(const Image& image) {
  return uint64_t(std::count_if(image.face_id.begin(), image.face_id.end(), [](uint32_t f) { return f != kNone; }));
}

TEST(ScreenImportance, AreasSumToTheCoveredPixelsMostFirst) {
  const Camera camera = looking_at(0.4f, 0.3f, 3.0f, 0, 0, 0);
  ClientMesh c(make_sphere(24, 32), camera, 1.0f);
  ASSERT_GT(c.hierarchy.size(), c.hierarchy.root_count()) << "refined past the base mesh";
  client::ScreenImportance importance(RenderOptions{1});
  const std::vector<client::VertexArea>& ranked = importance.rank(*c.mesh, c.view(camera));
  const uint64_t covered = pixels_with_a_face(importance.image());
  EXPECT_EQ(importance.covered_pixels(), covered);
  EXPECT_GT(covered, 1000u);
  EXPECT_LT(covered, uint64_t(camera.width) * camera.height) << "the sphere does not fill the viewport";
  uint64_t sum = 0;
  std::set<uint32_t> slots;
  for (size_t i = 0; i < ranked.size(); ++i) {
    sum += ranked[i].pixels;
    EXPECT_GT(ranked[i].pixels, 0u);
    EXPECT_TRUE(c.mesh->is_active(ranked[i].slot) && c.hierarchy.is_leaf(ranked[i].slot));
    EXPECT_TRUE(slots.insert(ranked[i].slot).second) << "ranked twice";
    if (i > 0) {
      EXPECT_GE(ranked[i - 1].pixels, ranked[i].pixels) << "most pixels first";
      if (ranked[i - 1].pixels == ranked[i].pixels) {
        EXPECT_LT(ranked[i - 1].slot, ranked[i].slot) << "ties by slot";
      }
    }
  }
  // Every covered pixel belongs to one face, and counts once for each of its corners that is ranked: the
  // leaves of the partial hierarchy (an active vertex whose split is known is not).
  const MeshArrays& arrays = importance.mesh_arrays();
  uint64_t expected = 0;
  for (uint32_t face : importance.image().face_id)
    if (face != kNone)
      for (size_t k = 0; k < 3; ++k)
        expected += c.hierarchy.is_leaf(arrays.slots[arrays.indices[3 * size_t(face) + k]]);
  EXPECT_EQ(sum, expected);
  EXPECT_LE(sum, 3 * covered);
  EXPECT_GT(sum, 2 * covered) << "most corners are leaves";
  // Only the visible half: the far side's vertices are hidden and not ranked.
  EXPECT_LT(ranked.size(), c.mesh->vertex_count());
  EXPECT_GT(ranked.size(), c.mesh->vertex_count() / 4);
}

TEST(ScreenImportance, AVertexBehindTheCameraGetsNoArea) {
  // Over the middle of a unit grid, looking along +x: the half with x < 0.5 is behind the camera.
  const Camera camera = looking_at(0.5f, 0.5f, 0.15f, 1.0f, 0.5f, 0.0f);
  ClientMesh c(make_grid(24, 24), camera, 0);
  client::ScreenImportance importance(RenderOptions{1});
  const std::vector<client::VertexArea>& ranked = importance.rank(*c.mesh, c.view(camera));
  ASSERT_FALSE(ranked.empty());
  std::set<uint32_t> ranked_slots;
  for (const client::VertexArea& v : ranked) ranked_slots.insert(v.slot);
  // A vertex whose every face lies wholly behind the eye's plane cannot show.
  const MeshArrays& arrays = importance.mesh_arrays();
  const auto behind = [&](uint32_t v) { return arrays.positions[3 * size_t(v)] < camera.eye[0]; };
  std::vector<bool> all_faces_behind(arrays.slots.size(), true);
  for (size_t f = 0; f < arrays.indices.size(); f += 3) {
    const bool face_behind =
        behind(arrays.indices[f]) && behind(arrays.indices[f + 1]) && behind(arrays.indices[f + 2]);
    for (size_t k = 0; k < 3; ++k)
      all_faces_behind[arrays.indices[f + k]] = all_faces_behind[arrays.indices[f + k]] && face_behind;
  }
  size_t hidden = 0;
  for (size_t v = 0; v < arrays.slots.size(); ++v) {
    if (!all_faces_behind[v]) continue;
    ++hidden;
    EXPECT_FALSE(ranked_slots.count(arrays.slots[v])) << "slot " << arrays.slots[v] << " is behind the camera";
  }
  EXPECT_GT(hidden, 5u);
  // Turned around, nothing of the grid is in front: nothing is ranked.
  const Camera away = looking_at(1.2f, 0.5f, 0.15f, 2.0f, 0.5f, 0.15f);
  EXPECT_TRUE(importance.rank(*c.mesh, c.view(away)).empty());
  EXPECT_EQ(importance.covered_pixels(), 0u);
}

TEST(ScreenImportance, OnlyVerticesThatCanSplitAreRanked) {
  const Camera camera = looking_at(0.4f, 0.3f, 3.0f, 0, 0, 0);
  ClientMesh c(make_sphere(16, 24), camera, 0);
  client::ScreenImportance importance(RenderOptions{1});
  const std::vector<client::VertexArea> all = importance.rank(*c.mesh, c.view(camera));
  ASSERT_GE(all.size(), 3u);
  const uint32_t top = all.front().slot;
  const std::vector<client::VertexArea> rest =
      importance.rank(*c.mesh, c.view(camera), [top](uint32_t slot) { return slot != top; });
  ASSERT_EQ(rest.size(), all.size() - 1);
  for (size_t i = 0; i < rest.size(); ++i) {
    EXPECT_EQ(rest[i].slot, all[i + 1].slot);
    EXPECT_EQ(rest[i].pixels, all[i + 1].pixels);
  }
}

// The browser's source (client/face_id_importance.h) handed the same frame as the page would draw it, face
// slot + 1 in RGB, ranks exactly as the software renderer's: the counting is shared.
TEST(FaceIdImportance, RanksAsTheRenderersFaceIdsDo) {
  const Camera camera = looking_at(0.4f, 0.3f, 3.0f, 0, 0, 0);
  ClientMesh c(make_sphere(24, 32), camera, 1.0f);
  client::ScreenImportance screen(RenderOptions{1});
  const std::vector<client::VertexArea> want = screen.rank(*c.mesh, c.view(camera));
  ASSERT_FALSE(want.empty());
  // extract() lists the live face slots in order: the renderer's face k is the k-th live slot.
  std::vector<uint32_t> slot_of_face;
  for (uint32_t f = 0; f < c.mesh->face_capacity(); ++f)
    if (c.mesh->face_alive(f)) slot_of_face.push_back(f);
  const Image& image = screen.image();
  ASSERT_EQ(slot_of_face.size(), screen.mesh_arrays().indices.size() / 3);
  std::vector<uint8_t> rgba(image.face_id.size() * 4, 0);
  for (size_t p = 0; p < image.face_id.size(); ++p) {
    if (image.face_id[p] == kNone) continue;
    const uint32_t id = slot_of_face[image.face_id[p]] + 1;
    rgba[4 * p] = uint8_t(id), rgba[4 * p + 1] = uint8_t(id >> 8), rgba[4 * p + 2] = uint8_t(id >> 16);
    rgba[4 * p + 3] = 255;
  }
  client::FaceIdImportance face_ids;
  EXPECT_TRUE(face_ids.rank(*c.mesh, c.view(camera), {}).empty()) << "no frame yet: nothing ranked";
  face_ids.set_face_ids(rgba, camera.width, camera.height);
  const std::vector<client::VertexArea>& got = face_ids.rank(*c.mesh, c.view(camera), {});
  ASSERT_EQ(got.size(), want.size());
  for (size_t i = 0; i < got.size(); ++i) {
    EXPECT_EQ(got[i].slot, want[i].slot);
    EXPECT_EQ(got[i].pixels, want[i].pixels);
  }
  EXPECT_THROW(face_ids.set_face_ids(rgba, camera.width + 1, camera.height), Error);
  // Ids past the mesh's faces (a stale frame) count for nothing.
  std::vector<uint8_t> stale(rgba.size(), 0xFF);
  face_ids.set_face_ids(stale, camera.width, camera.height);
  EXPECT_TRUE(face_ids.rank(*c.mesh, c.view(camera), {}).empty());
}

}  // namespace
}  // namespace pms
