// Property 1 (docs/architecture.md, "Correctness properties") with the real builder: refining every split
// of a built .pms file gives back the cleaned input (same positions, same faces up to renumbering, same
// orientation), in stream order and in breadth-first order alike; no splits gives the base mesh.
#include <gtest/gtest.h>
#include <algorithm>
#include <array>
#include <vector>

#include "builder/build.h"
#include "io/shapes.h"
#include "spm/hierarchy.h"
#include "spm/pms_file.h"
#include "spm/selective_mesh.h"
#include "spm/split_record.h"
#include "spm/stream_order.h"
#include "spm/vertex_hierarchy.h"
#include "test_support.h"

namespace pms {
namespace {

using Corner = std::array<float, 3>;
using Face = std::array<Corner, 3>;

// Faces as position triples rotated to start at their smallest corner: equal for the same
// oriented face whatever the vertex numbering.
std::vector<Face> canonical_faces(const std::vector<float>& positions, const std::vector<uint32_t>& indices) {
  std::vector<Face> faces;
  for (size_t f = 0; f + 2 < indices.size(); f += 3) {
    Face face;
    for (int k = 0; k < 3; ++k)
      face[k] = {positions[3 * size_t(indices[f + k])], positions[3 * size_t(indices[f + k]) + 1],
                 positions[3 * size_t(indices[f + k]) + 2]};
    std::rotate(face.begin(), std::min_element(face.begin(), face.end()), face.end());
    faces.push_back(face);
  }
  std::sort(faces.begin(), faces.end());
  return faces;
}

std::unique_ptr<PmsFile> build_and_open(const Mesh& mesh, const BuildOptions& options) {
  const BuildResult built = build_progressive_mesh(mesh, options);
  const auto path = (test::temp_dir() / "model.pms").string();
  write_pms(path, built.hierarchy, built.stats);
  return PmsFile::open(path);
}

void expect_full_refinement_is_input(const Mesh& mesh, const BuildOptions& options = {}) {
  const auto file = build_and_open(mesh, options);
  const ModelData& model = file->model();
  const MeshArrays full = refine_in_stream_order(model, UINT64_MAX);
  EXPECT_EQ(full.positions.size(), mesh.positions.size());
  EXPECT_EQ(canonical_faces(full.positions, full.indices), canonical_faces(mesh.positions, mesh.indices));

  const MeshArrays base = refine_in_stream_order(model, 0);
  EXPECT_EQ(base.indices.size(), model.base_faces.size());
  EXPECT_EQ(base.positions.size() / 3, model.root_count);

  // Breadth-first (array) order: the engine applies the partial order of kim-lee-kobbelt §5.3.
  VertexHierarchy hierarchy = VertexHierarchy::from_model(model);
  for (uint32_t n = 0; n < model.node_count(); ++n)
    if (!model.is_leaf(n)) hierarchy.add_split(split_record(model, n));
  SelectiveMesh selective(hierarchy, model.base_faces);
  for (uint32_t n = 0; n < model.node_count(); ++n) {
    if (model.is_leaf(n)) continue;
    const uint32_t slot = hierarchy.find(model.id(n));
    if (selective.is_active(slot)) {
      ASSERT_TRUE(selective.vsplit(slot).done);
    }
  }
  std::string why;
  ASSERT_TRUE(selective.check_invariants(&why)) << why;
  MeshArrays bfs;
  selective.extract(bfs);
  EXPECT_EQ(canonical_faces(bfs.positions, bfs.indices), canonical_faces(mesh.positions, mesh.indices));
}

TEST(Reconstruct, Sphere) { expect_full_refinement_is_input(make_sphere(20, 28)); }
TEST(Reconstruct, Torus) { expect_full_refinement_is_input(make_torus(30, 12, 1.0f, 0.35f)); }
TEST(Reconstruct, OpenGrid) { expect_full_refinement_is_input(make_grid(25, 17)); }

TEST(Reconstruct, RepairedNonManifoldFixture) {
  Mesh mesh = make_nonmanifold_fixture();
  clean_mesh(mesh);
  expect_full_refinement_is_input(mesh);
}

TEST(Reconstruct, GreedyOrder) {
  BuildOptions options;
  options.greedy = true;
  expect_full_refinement_is_input(make_sphere(16, 20), options);
}

TEST(Reconstruct, Bunny) {
  PMS_REQUIRE_SHARED_MODEL(path, "bunny.ply.xz");
  Mesh mesh = load_mesh(path.string());
  clean_mesh(mesh);
  expect_full_refinement_is_input(mesh);
}

TEST(Reconstruct, TerrainWithAsCoarseAsPossibleBase) {
  BuildOptions options;
  options.base_vertices = 0;
  expect_full_refinement_is_input(make_terrain(20000, 7), options);
}

}  // namespace
}  // namespace pms
