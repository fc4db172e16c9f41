// clean_mesh() and the generated shapes: the builder's input contract (an oriented 2-manifold).
#include <gtest/gtest.h>

#include <set>

#include "io/manifold_check.h"
#include "io/mesh.h"
#include "io/shapes.h"
#include "common/error.h"
#include "test_support.h"

namespace pms {
namespace {

long euler_characteristic(const Mesh& m) {
  std::set<std::pair<uint32_t, uint32_t>> edges;
  for (size_t f = 0; f < m.face_count(); ++f)
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = m.indices[3 * f + k], b = m.indices[3 * f + (k + 1) % 3];
      edges.insert({std::min(a, b), std::max(a, b)});
    }
  return long(m.vertex_count()) - long(edges.size()) + long(m.face_count());
}

TEST(Shapes, AreOrientedManifoldsWithTheRightTopology) {
  std::string why;
  const Mesh sphere = make_sphere(12, 16), torus = make_torus(20, 10, 1, 0.3f), grid = make_grid(9, 7);
  EXPECT_TRUE(is_oriented_manifold(sphere, &why)) << why;
  EXPECT_TRUE(is_oriented_manifold(torus, &why)) << why;
  EXPECT_TRUE(is_oriented_manifold(grid, &why)) << why;
  EXPECT_EQ(euler_characteristic(sphere), 2);
  EXPECT_EQ(euler_characteristic(torus), 0);
  EXPECT_EQ(euler_characteristic(grid), 1);
}

TEST(Shapes, TerrainIsDeterministicAndNearTheTarget) {
  const Mesh a = make_terrain(100000, 3), b = make_terrain(100000, 3), c = make_terrain(100000, 4);
  EXPECT_EQ(a.positions, b.positions);
  EXPECT_EQ(a.indices, b.indices);
  EXPECT_NE(a.positions, c.positions);
  EXPECT_NEAR(double(a.face_count()), 100000.0, 1000.0);
  std::string why;
  EXPECT_TRUE(is_oriented_manifold(a, &why)) << why;
}

TEST(Clean, RepairsTheNonManifoldFixture) {
  Mesh mesh = make_nonmanifold_fixture();
  std::string why;
  ASSERT_FALSE(is_oriented_manifold(mesh, &why));
  const CleanReport report = clean_mesh(mesh);
  EXPECT_TRUE(is_oriented_manifold(mesh, &why)) << why;
  EXPECT_EQ(report.welded_vertices, 1u);      // vertex 12 sits on vertex 3
  EXPECT_EQ(report.degenerate_faces, 1u);     // (1, 1, 2)
  EXPECT_EQ(report.duplicate_faces, 1u);      // (1, 2, 3) twice
  EXPECT_GE(report.nonmanifold_edges, 2u);    // the book's spine and the tetrahedron edge with a third face
  EXPECT_GE(report.nonmanifold_vertices, 1u); // the vertex the two tetrahedra share
  EXPECT_GE(report.split_vertex_copies, report.nonmanifold_vertices);
}

TEST(Clean, WeldsCoincidentVerticesAndKeepsAttributesInStep) {
  // Two triangles of a quad, each with its own copies of the shared corners.
  Mesh mesh;
  mesh.positions = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 0, 0, 1, 1, 0, 0, 1, 0, 5, 5, 5};
  mesh.colors = {1, 0, 0, 255, 2, 0, 0, 255, 3, 0, 0, 255, 9, 9, 9, 255, 9, 9, 9, 255, 6, 0, 0, 255, 7, 7, 7, 255};
  mesh.indices = {0, 1, 2, 3, 4, 5};
  const CleanReport report = clean_mesh(mesh);
  EXPECT_EQ(report.welded_vertices, 2u);
  EXPECT_EQ(report.unreferenced_vertices, 1u);
  ASSERT_EQ(mesh.vertex_count(), 4u);
  ASSERT_EQ(mesh.colors.size(), 16u);
  EXPECT_EQ(mesh.colors[0], 1);  // the first copy's attributes win
  EXPECT_EQ(mesh.colors[8], 3);
  EXPECT_EQ(mesh.colors[12], 6);
  EXPECT_TRUE(is_oriented_manifold(mesh));
}

TEST(Clean, OrientsFacesConsistently) {
  Mesh mesh = make_sphere(10, 12);
  const size_t faces = mesh.face_count();
  for (size_t f = 0; f < faces; f += 7) std::swap(mesh.indices[3 * f + 1], mesh.indices[3 * f + 2]);
  const CleanReport report = clean_mesh(mesh);
  EXPECT_TRUE(is_oriented_manifold(mesh));
  EXPECT_EQ(report.flipped_faces, (faces + 6) / 7);  // the minority is flipped back
  // Outward: the first face's normal points away from the centre.
  const float* a = &mesh.positions[3 * size_t(mesh.indices[0])];
  const float* b = &mesh.positions[3 * size_t(mesh.indices[1])];
  const float* c = &mesh.positions[3 * size_t(mesh.indices[2])];
  const float n[3] = {(b[1] - a[1]) * (c[2] - a[2]) - (b[2] - a[2]) * (c[1] - a[1]),
                      (b[2] - a[2]) * (c[0] - a[0]) - (b[0] - a[0]) * (c[2] - a[2]),
                      (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])};
  EXPECT_GT(n[0] * (a[0] + b[0] + c[0]) + n[1] * (a[1] + b[1] + c[1]) + n[2] * (a[2] + b[2] + c[2]), 0.0f);
}

TEST(Clean, RealScansComeOutManifold) {
  PMS_REQUIRE_SHARED_MODEL(path, "bunny_res2.ply.xz");  // Stanford's decimation: duplicates, non-manifold edges
  Mesh mesh = load_mesh(path.string());
  const CleanReport report = clean_mesh(mesh);
  std::string why;
  EXPECT_TRUE(is_oriented_manifold(mesh, &why)) << why;
  EXPECT_EQ(report.duplicate_faces, 87u);
}

TEST(Clean, EmptyResultIsAnError) {
  Mesh mesh;
  mesh.positions = {0, 0, 0, 1, 0, 0, 2, 0, 0};
  mesh.indices = {0, 1, 2};  // collinear: zero area
  EXPECT_THROW(clean_mesh(mesh), Error);
}

}  // namespace
}  // namespace pms
