// The mesh as a renderer's buffers: slot-numbered arrays that draw the same triangles as the extracted
// mesh, changed ranges that cover every entry that changed and nothing when nothing did, geomorphs'
// shown positions, normals computed where the model has none.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "client/mesh_buffers.h"
#include "fixtures/view_models.h"

namespace pms::client {
namespace {

// Every element of `after` that differs from `before` (or is new) lies in one of `ranges`, which are
// increasing and disjoint.
template <class T>
void expect_covered(const std::vector<T>& before, const std::vector<T>& after, size_t per_element,
                    const std::vector<BufferRange>& ranges) {
  for (size_t r = 1; r < ranges.size(); ++r) EXPECT_GE(ranges[r].first, ranges[r - 1].first + ranges[r - 1].count);
  for (size_t i = 0; i < after.size(); ++i) {
    if (i < before.size() && before[i] == after[i]) continue;
    const size_t element = i / per_element;
    const bool covered = std::any_of(ranges.begin(), ranges.end(), [&](const BufferRange& range) {
      return element >= range.first && element < size_t(range.first) + range.count;
    });
    ASSERT_TRUE(covered) << "element " << element << " changed outside the ranges";
  }
}

struct Refined {
  VertexHierarchy hierarchy;
  SelectiveMesh mesh;
  SelectiveRefinement refinement;
  Refined(const test::BuiltModel& model, uint32_t morph_frames)
      : hierarchy(test::complete_hierarchy(model.model())),
        mesh(hierarchy, model.model().base_faces),
        refinement(mesh, model.h.scale, options(morph_frames)) {}
  static AdaptOptions options(uint32_t morph_frames) {
    AdaptOptions o;
    o.morph_frames = morph_frames;
    return o;
  }
};

TEST(MeshBuffers, DrawTheExtractedMeshAndReportWhatChanged) {
  const test::BuiltModel& model = test::built_terrain();
  for (uint32_t morph_frames : {0u, 4u}) {
    Refined r(model, morph_frames);
    MeshBuffers buffers;
    for (float distance : {3.0f, 1.2f, 0.6f, 2.0f}) {
      r.refinement.set_view(test::view_for(model, test::framing_camera(model, {0.3f, -1, 0.8f}, distance)));
      for (int frame = 0; frame < 6; ++frame) {
        r.refinement.adapt();
        const MeshBuffers before = buffers;
        update_buffers(r.refinement, buffers);
        expect_covered(before.positions, buffers.positions, 3, buffers.changed_vertices);
        expect_covered(before.normals, buffers.normals, 3, buffers.changed_vertices);
        expect_covered(before.indices, buffers.indices, 3, buffers.changed_triangles);
        MeshArrays extracted;
        r.refinement.extract(extracted);
        ASSERT_EQ(positioned_triangles(buffers.positions, buffers.indices),
                  positioned_triangles(extracted.positions, extracted.indices))
            << "distance " << distance << ", frame " << frame << ", morph frames " << morph_frames;
      }
      // Nothing moved: nothing to upload.
      r.refinement.converge();
      update_buffers(r.refinement, buffers);
      update_buffers(r.refinement, buffers);
      EXPECT_TRUE(buffers.changed_vertices.empty());
      EXPECT_TRUE(buffers.changed_triangles.empty());
    }
  }
}

TEST(MeshBuffers, NormalsAreComputedWhereTheModelHasNone) {
  const test::BuiltModel& model = test::built_sphere();
  Refined r(model, 0);
  r.refinement.set_view(test::view_for(model, test::framing_camera(model, {0, 0, 1}, 1.5f)));
  r.refinement.converge();
  MeshBuffers buffers;
  update_buffers(r.refinement, buffers);
  ASSERT_FALSE(r.hierarchy.has_normals());
  for (uint32_t v : r.mesh.active_vertices()) {
    const float* n = &buffers.normals[3 * size_t(v)];
    EXPECT_NEAR(std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]), 1.0f, 1e-4f) << "slot " << v;
    // On a sphere about its centre the normal points away from it.
    const float* p = r.hierarchy.position(v);
    const float* c = model.h.bbox_min;
    const float* d = model.h.bbox_max;
    const float out[3] = {p[0] - (c[0] + d[0]) / 2, p[1] - (c[1] + d[1]) / 2, p[2] - (c[2] + d[2]) / 2};
    EXPECT_GT(n[0] * out[0] + n[1] * out[1] + n[2] * out[2], 0.0f) << "slot " << v;
  }
}

TEST(MeshBuffers, AMeshNumberedItsOwnWayShrinksToDegenerateTriangles) {
  Mesh big;
  big.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0};
  big.indices = {0, 1, 2, 1, 3, 2};
  MeshBuffers buffers;
  update_buffers(big, buffers);
  EXPECT_EQ(buffers.changed_triangles, (std::vector<BufferRange>{{0, 2}}));
  EXPECT_EQ(buffers.changed_vertices, (std::vector<BufferRange>{{0, 4}}));
  Mesh small = big;
  small.indices = {0, 1, 2};
  update_buffers(small, buffers);
  EXPECT_EQ(buffers.changed_triangles, (std::vector<BufferRange>{{1, 1}}));
  EXPECT_EQ(std::vector<uint32_t>(buffers.indices.begin() + 3, buffers.indices.end()), (std::vector<uint32_t>{0, 0, 0}));
  EXPECT_EQ(buffers.colors[0], 255);  // opaque white without the model's colours
}

}  // namespace
}  // namespace pms::client
