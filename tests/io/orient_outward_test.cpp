// Cleaning's last step: closed components wound inside out face outward again, cavities and open surfaces
// keep their winding (io/orient_outward.h).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <utility>
#include <vector>

#include "io/manifold_check.h"
#include "io/mesh.h"
#include "io/orient_outward.h"
#include "io/shapes.h"

namespace pms {
namespace {

void reverse_winding(Mesh& mesh, size_t first_face = 0, size_t end_face = SIZE_MAX) {
  for (size_t f = first_face; f < std::min(end_face, mesh.face_count()); ++f)
    std::swap(mesh.indices[3 * f + 1], mesh.indices[3 * f + 2]);
}

// The vertex normals a scanner would write for this winding: each vertex's position from the centre.
void add_radial_normals(Mesh& mesh, float sign) {
  mesh.normals.assign(mesh.positions.begin(), mesh.positions.end());
  for (float& n : mesh.normals) n *= sign;
}

// Appends `part` (its vertices moved by `offset` and scaled by `scale`) to `mesh` as its own component.
void append(Mesh& mesh, const Mesh& part, float scale, float offset) {
  const uint32_t base = uint32_t(mesh.vertex_count());
  for (float p : part.positions) mesh.positions.push_back(p * scale + offset);
  for (float n : part.normals) mesh.normals.push_back(n);
  for (uint32_t v : part.indices) mesh.indices.push_back(base + v);
}

TEST(OrientOutward, AnInsideOutSphereIsTurnedOutwardWithItsNormals) {
  Mesh outward = make_sphere(10, 12);
  add_radial_normals(outward, 1);
  Mesh mesh = outward;
  reverse_winding(mesh);
  add_radial_normals(mesh, -1);
  const OutwardReport report = orient_closed_components_outward(mesh);
  EXPECT_EQ(report.components, 1u);
  EXPECT_EQ(report.faces, outward.face_count());
  EXPECT_EQ(mesh.indices, outward.indices);
  EXPECT_EQ(mesh.normals, outward.normals);
  EXPECT_TRUE(is_oriented_manifold(mesh));

  const CleanReport again = clean_mesh(mesh);  // through the cleaner: nothing left to turn
  EXPECT_EQ(again.inside_out_components, 0u);
  EXPECT_EQ(mesh.indices, outward.indices);
}

TEST(OrientOutward, CleaningReportsTheTurn) {
  Mesh mesh = make_torus(12, 16, 2.0f, 0.5f);
  const Mesh outward = mesh;
  reverse_winding(mesh);
  const CleanReport report = clean_mesh(mesh);
  EXPECT_EQ(report.inside_out_components, 1u);
  EXPECT_EQ(report.inside_out_faces, outward.face_count());
  EXPECT_EQ(report.flipped_faces, 0u);  // the winding was consistent, only inside out
  EXPECT_EQ(mesh.indices, outward.indices);
}

TEST(OrientOutward, OnlyTheInsideOutComponentTurns) {
  const Mesh sphere = make_sphere(8, 10);
  Mesh mesh;
  append(mesh, sphere, 1, 0);
  Mesh inside_out = sphere;
  reverse_winding(inside_out);
  append(mesh, inside_out, 1, 5);  // beside the first, not inside it
  const OutwardReport report = orient_closed_components_outward(mesh);
  EXPECT_EQ(report.components, 1u);
  EXPECT_EQ(report.faces, sphere.face_count());
  Mesh expected;
  append(expected, sphere, 1, 0);
  append(expected, sphere, 1, 5);
  EXPECT_EQ(mesh.indices, expected.indices);
}

// A hollow shell: the outer wall faces out, the inner wall faces the cavity (negative volume, enclosed
// once). Both stay; the whole shell inside out turns both.
TEST(OrientOutward, ACavityKeepsFacingInward) {
  const Mesh sphere = make_sphere(10, 12);
  Mesh inner = sphere;
  reverse_winding(inner);
  Mesh shell;
  append(shell, sphere, 1, 0);
  append(shell, inner, 0.5f, 0.01f);
  const Mesh as_built = shell;
  EXPECT_EQ(orient_closed_components_outward(shell).components, 0u);
  EXPECT_EQ(shell.indices, as_built.indices);

  Mesh inside_out = as_built;
  reverse_winding(inside_out);
  const OutwardReport report = orient_closed_components_outward(inside_out);
  EXPECT_EQ(report.components, 2u);
  EXPECT_EQ(inside_out.indices, as_built.indices);
}

TEST(OrientOutward, OpenSurfacesKeepTheirWinding) {
  for (Mesh mesh : {make_grid(6, 5), make_terrain(2000)}) {
    reverse_winding(mesh);
    const Mesh before = mesh;
    EXPECT_EQ(orient_closed_components_outward(mesh).components, 0u);
    EXPECT_EQ(mesh.indices, before.indices);
  }
  Mesh cut_sphere = make_sphere(10, 12);  // a sphere with one face missing is open too
  reverse_winding(cut_sphere);
  cut_sphere.indices.resize(cut_sphere.indices.size() - 3);
  const Mesh before = cut_sphere;
  EXPECT_EQ(orient_closed_components_outward(cut_sphere).components, 0u);
  EXPECT_EQ(cut_sphere.indices, before.indices);
}

// Side by side, both inside out: the closed sphere turns, the one with a face missing (a boundary whose
// vertices sit in one component with interior ones) keeps its winding.
TEST(OrientOutward, OnlyTheClosedOfTwoInsideOutComponentsTurns) {
  const Mesh sphere = make_sphere(10, 12);
  Mesh cut = sphere;
  cut.indices.resize(cut.indices.size() - 3);
  Mesh expected;
  append(expected, sphere, 1, 0);
  append(expected, cut, 1, 5);
  Mesh mesh = expected;
  reverse_winding(mesh);
  reverse_winding(expected, sphere.face_count());  // the cut sphere's faces stay reversed
  const OutwardReport report = orient_closed_components_outward(mesh);
  EXPECT_EQ(report.components, 1u);
  EXPECT_EQ(report.faces, sphere.face_count());
  EXPECT_EQ(mesh.indices, expected.indices);
}

}  // namespace
}  // namespace pms
