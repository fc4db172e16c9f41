// clean_mesh() and is_oriented_manifold(): the builder's input contract (an oriented 2-manifold).
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <random>

#include "common/error.h"
#include "io/manifold_check.h"
#include "io/mesh.h"
#include "io/shapes.h"
#include "test_support.h"

namespace pms {
namespace {

std::array<float, 3> point(const Mesh& m, uint32_t v) {
  return {m.positions[3 * size_t(v)], m.positions[3 * size_t(v) + 1], m.positions[3 * size_t(v) + 2]};
}

// Tags every vertex with its index in the colors (r g b = low, mid, high byte) and derives a normal and
// texture coordinates from it, so a cleaned vertex can be traced back to the input vertex it came from.
void tag_vertices(Mesh& m) {
  m.colors.clear();
  m.normals.clear();
  m.texcoords.clear();
  for (uint32_t v = 0; v < m.vertex_count(); ++v) {
    m.colors.insert(m.colors.end(), {uint8_t(v), uint8_t(v >> 8), uint8_t(v >> 16), 255});
    m.normals.insert(m.normals.end(), {float(v), -float(v), 0.5f});
    m.texcoords.insert(m.texcoords.end(), {0.5f * float(v), 0.25f});
  }
}

uint32_t tag_of(const Mesh& m, uint32_t v) {
  return m.colors[4 * size_t(v)] | uint32_t(m.colors[4 * size_t(v) + 1]) << 8 |
         uint32_t(m.colors[4 * size_t(v) + 2]) << 16;
}

// Every cleaned vertex still carries the position, normal and color of one input vertex, in step.
void expect_attributes_in_step(const Mesh& input, const Mesh& cleaned) {
  ASSERT_EQ(cleaned.normals.size(), cleaned.positions.size());
  ASSERT_EQ(cleaned.colors.size(), 4 * cleaned.vertex_count());
  ASSERT_EQ(cleaned.texcoords.size(), 2 * cleaned.vertex_count());
  for (uint32_t v = 0; v < cleaned.vertex_count(); ++v) {
    const uint32_t source = tag_of(cleaned, v);
    ASSERT_LT(source, input.vertex_count());
    EXPECT_EQ(point(cleaned, v), point(input, source)) << "vertex " << v;
    // Negated where cleaning turned a closed component outward.
    const float sign = cleaned.normals[3 * size_t(v) + 2] > 0 ? 1.0f : -1.0f;
    EXPECT_EQ(cleaned.normals[3 * size_t(v)], sign * float(source)) << "vertex " << v;
    EXPECT_EQ(cleaned.normals[3 * size_t(v) + 1], -sign * float(source)) << "vertex " << v;
    EXPECT_EQ(cleaned.texcoords[2 * size_t(v)], 0.5f * float(source)) << "vertex " << v;
    EXPECT_EQ(cleaned.colors[4 * size_t(v) + 3], 255);
  }
}

bool same_report(const CleanReport& a, const CleanReport& b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// ---- is_oriented_manifold ------------------------------------------------------------------------------

Mesh triangle_mesh(std::vector<float> positions, std::vector<uint32_t> indices) {
  Mesh m;
  m.positions = std::move(positions);
  m.indices = std::move(indices);
  return m;
}

const std::vector<float> kSquare = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0.5f, 0.5f, 1};

TEST(ManifoldCheck, AcceptsManifolds) {
  EXPECT_TRUE(is_oriented_manifold(triangle_mesh({0, 0, 0, 1, 0, 0, 0, 1, 0}, {0, 1, 2})));
  EXPECT_TRUE(is_oriented_manifold(make_sphere(6, 7)));
  EXPECT_TRUE(is_oriented_manifold(make_grid(4, 3)));
  // A pyramid without its floor: vertex 4's fan is a cycle, the others' are chains.
  EXPECT_TRUE(is_oriented_manifold(triangle_mesh(kSquare, {0, 1, 4, 1, 2, 4, 2, 3, 4, 3, 0, 4})));
}

TEST(ManifoldCheck, NamesEachViolation) {
  auto why = [](const Mesh& m) {
    std::string text;
    EXPECT_FALSE(is_oriented_manifold(m, &text));
    return text;
  };
  EXPECT_NE(why(triangle_mesh(kSquare, {0, 1, 7})).find("out of range"), std::string::npos);
  EXPECT_NE(why(triangle_mesh(kSquare, {0, 1, 1})).find("repeats a corner"), std::string::npos);
  EXPECT_NE(why(triangle_mesh({0, 0, 0, 1, 0, 0, 2, 0, 0}, {0, 1, 2})).find("zero area"), std::string::npos);
  EXPECT_NE(why(triangle_mesh(kSquare, {0, 1, 2, 3, 4, 0, 1, 2, 4, 0, 1})).find("multiple of 3"), std::string::npos);
  // Neighbours that disagree on the orientation of their shared edge.
  EXPECT_NE(why(triangle_mesh(kSquare, {0, 1, 2, 0, 1, 3, 2, 3, 4})).find("directed edge"), std::string::npos);
  // Three faces on edge 0-1.
  EXPECT_NE(why(triangle_mesh(kSquare, {0, 1, 2, 1, 0, 3, 0, 1, 4})).find("directed edge"), std::string::npos);
  // The same triangle twice, once each way (a closed "pillow").
  EXPECT_NE(why(triangle_mesh(kSquare, {0, 1, 2, 0, 2, 1, 3, 4, 0})).find("duplicate"), std::string::npos);
  // Two triangles touching only at vertex 0.
  EXPECT_NE(why(triangle_mesh(kSquare, {0, 1, 2, 0, 3, 4})).find("more than one fan"), std::string::npos);
  EXPECT_NE(why(triangle_mesh(kSquare, {0, 1, 2, 0, 2, 3})).find("not used by any face"), std::string::npos);
}

// ---- clean_mesh ----------------------------------------------------------------------------------------

TEST(Clean, RepairsTheNonManifoldFixture) {
  Mesh mesh = make_nonmanifold_fixture();
  tag_vertices(mesh);
  const Mesh input = mesh;
  const CleanReport report = clean_mesh(mesh);
  std::string why;
  EXPECT_TRUE(is_oriented_manifold(mesh, &why)) << why;
  EXPECT_EQ(report.welded_vertices, 1u);        // 12 sits on 3
  EXPECT_EQ(report.unreferenced_vertices, 1u);  // 14
  EXPECT_EQ(report.degenerate_faces, 2u);       // (1, 1, 2) and the collinear (7, 9, 10)
  EXPECT_EQ(report.duplicate_faces, 1u);        // (3, 2, 1) repeats (1, 2, 3) the other way round
  EXPECT_EQ(report.nonmanifold_edges, 2u);      // the book's spine 7-8 and 1-3 with a third face
  EXPECT_EQ(report.nonmanifold_vertices, 5u);   // 0 (two tetrahedra), 7 and 8, 1 and 3
  EXPECT_EQ(report.split_vertex_copies, 5u);
  EXPECT_EQ(report.flipped_faces, 1u);  // (15, 18, 17)
  EXPECT_EQ(mesh.vertex_count(), 19u - 1 - 1 + 5);
  EXPECT_EQ(mesh.face_count(), 17u - 3);
  expect_attributes_in_step(input, mesh);
  // The first welded vertex wins: 3's attributes, never 12's.
  for (uint32_t v = 0; v < mesh.vertex_count(); ++v) EXPECT_NE(tag_of(mesh, v), 12u);
}

TEST(Clean, IsIdempotentAndLeavesManifoldsAlone) {
  Mesh once = make_nonmanifold_fixture();
  const CleanReport first = clean_mesh(once);
  // The copies of split vertices coincide with their originals, so a second pass welds them and splits
  // them again, the same way.
  Mesh twice = once;
  const CleanReport second = clean_mesh(twice);
  EXPECT_EQ(second.welded_vertices, first.split_vertex_copies);
  EXPECT_EQ(second.split_vertex_copies, first.split_vertex_copies);
  EXPECT_EQ(second.flipped_faces + second.degenerate_faces + second.duplicate_faces, 0u);
  EXPECT_EQ(twice.positions, once.positions);
  EXPECT_EQ(twice.indices, once.indices);

  const Mesh torus = make_torus(12, 8, 1, 0.25f);
  Mesh cleaned = torus;
  EXPECT_TRUE(same_report(clean_mesh(cleaned), CleanReport{}));
  EXPECT_EQ(cleaned.indices, torus.indices);
  EXPECT_EQ(cleaned.positions, torus.positions);
}

TEST(Clean, WeldsCoincidentVerticesKeepingTheFirstAttributes) {
  // Two triangles of a quad, each with its own copies of the shared corners; one copy has -0.
  Mesh mesh;
  mesh.positions = {0, 0, 0, 1, 0, 0, 1, 1, 0, -0.0f, 0, 0, 1, 1, -0.0f, 0, 1, 0, 5, 5, 5};
  mesh.colors = {1, 0, 0, 255, 2, 0, 0, 255, 3, 0, 0, 255, 9, 9, 9, 255, 9, 9, 9, 255, 6, 0, 0, 255, 7, 7, 7, 255};
  mesh.normals = {0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 1, 0, 0, 1, 0, 0, 0, 1, 1, 0, 0};
  mesh.texcoords = {0, 0, 1, 0, 1, 1, 0.5f, 0.5f, 0.5f, 0.5f, 0, 1, 9, 9};  // the copies differ: a seam
  mesh.indices = {0, 1, 2, 3, 4, 5};
  const CleanReport report = clean_mesh(mesh);
  EXPECT_EQ(report.welded_vertices, 2u);
  EXPECT_EQ(report.unreferenced_vertices, 1u);
  EXPECT_EQ(mesh.indices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3}));
  EXPECT_EQ(mesh.colors, (std::vector<uint8_t>{1, 0, 0, 255, 2, 0, 0, 255, 3, 0, 0, 255, 6, 0, 0, 255}));
  EXPECT_EQ(mesh.normals, (std::vector<float>{0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1}));
  EXPECT_EQ(mesh.texcoords, (std::vector<float>{0, 0, 1, 0, 1, 1, 0, 1}));
  EXPECT_TRUE(is_oriented_manifold(mesh));
}

TEST(Clean, WeldsATriangleSoupBackIntoTheSphere) {
  const Mesh sphere = make_sphere(10, 12);
  Mesh soup;  // every face with its own three vertices
  for (uint32_t v : sphere.indices) {
    const auto p = point(sphere, v);
    soup.positions.insert(soup.positions.end(), p.begin(), p.end());
    soup.indices.push_back(uint32_t(soup.indices.size()));
  }
  const CleanReport report = clean_mesh(soup);
  EXPECT_EQ(soup.vertex_count(), sphere.vertex_count());
  EXPECT_EQ(report.welded_vertices, sphere.indices.size() - sphere.vertex_count());
  EXPECT_EQ(soup.face_count(), sphere.face_count());
  EXPECT_EQ(report.nonmanifold_edges + report.nonmanifold_vertices + report.flipped_faces, 0u);
  std::string why;
  EXPECT_TRUE(is_oriented_manifold(soup, &why)) << why;
  for (size_t c = 0; c < soup.indices.size(); ++c)  // the same corners in the same places
    EXPECT_EQ(point(soup, soup.indices[c]), point(sphere, sphere.indices[c]));
}

TEST(Clean, FlipsTheMinorityBackOutward) {
  const Mesh sphere = make_sphere(10, 12);
  Mesh mesh = sphere;
  size_t reversed = 0;
  for (size_t f = 0; f < mesh.face_count(); f += 7, ++reversed)  // face 0 too: the first face is not trusted
    std::swap(mesh.indices[3 * f + 1], mesh.indices[3 * f + 2]);
  const CleanReport report = clean_mesh(mesh);
  EXPECT_EQ(report.flipped_faces, reversed);
  EXPECT_EQ(report.nonmanifold_edges, 0u);
  EXPECT_EQ(mesh.indices, sphere.indices);  // exactly the outward sphere again
}

// A half-twisted strip cannot be oriented: exactly one edge is cut, which splits its two end vertices.
TEST(Clean, CutsAMobiusStripOpen) {
  const int n = 24;
  Mesh strip;
  for (int i = 0; i < n; ++i) {
    const float a = 2 * 3.14159265f * float(i) / n, twist = a / 2;
    for (float side : {-0.3f, 0.3f}) {
      const float r = 1 + side * std::cos(twist);
      strip.positions.insert(strip.positions.end(), {r * std::cos(a), r * std::sin(a), side * std::sin(twist)});
    }
  }
  for (uint32_t i = 0; i < uint32_t(n); ++i) {
    const uint32_t a = 2 * i, b = 2 * i + 1;
    const bool last = i + 1 == uint32_t(n);  // the far end joins the start upside down
    const uint32_t c = last ? 1 : 2 * i + 2, d = last ? 0 : 2 * i + 3;
    strip.indices.insert(strip.indices.end(), {a, c, b, b, c, d});
  }
  tag_vertices(strip);
  const Mesh input = strip;
  const CleanReport report = clean_mesh(strip);
  std::string why;
  EXPECT_TRUE(is_oriented_manifold(strip, &why)) << why;
  EXPECT_EQ(report.nonmanifold_edges, 1u);
  EXPECT_EQ(report.split_vertex_copies, 2u);
  EXPECT_EQ(strip.face_count(), input.face_count());
  EXPECT_LE(2 * report.flipped_faces, input.face_count());  // the majority orientation stays
  expect_attributes_in_step(input, strip);
}

// Random triangle soups over a few shared points: every kind of defect at once, many times.
TEST(Clean, RandomSoupsBecomeOrientedManifolds) {
  std::mt19937 random(12345);  // the engine's sequence is fixed by the standard (distributions are not)
  size_t cuts = 0, copies = 0, empty = 0;
  for (int round = 0; round < 300; ++round) {
    Mesh soup;
    const uint32_t points = 6 + random() % 6, vertices = points + random() % 4, faces = 4 + random() % 30;
    std::vector<std::array<float, 3>> spots(points);
    for (auto& p : spots)
      for (float& x : p) x = float(random() % 1000) / 100 - 5;
    for (uint32_t v = 0; v < vertices; ++v) {
      const auto& p = spots[v < points ? v : random() % points];  // extra vertices sit on earlier ones
      soup.positions.insert(soup.positions.end(), p.begin(), p.end());
    }
    for (uint32_t k = 0; k < 3 * faces; ++k) soup.indices.push_back(random() % vertices);
    tag_vertices(soup);
    Mesh cleaned = soup;
    CleanReport report;
    try {
      report = clean_mesh(cleaned);
    } catch (const Error& e) {  // only when every face drawn was degenerate, which is rare
      EXPECT_NE(std::string(e.what()).find("no faces left"), std::string::npos) << e.what();
      ++empty;
      continue;
    }
    std::string why;
    ASSERT_TRUE(is_oriented_manifold(cleaned, &why)) << "round " << round << ": " << why;
    expect_attributes_in_step(soup, cleaned);
    Mesh again = soup;
    EXPECT_TRUE(same_report(clean_mesh(again), report)) << "round " << round;
    EXPECT_EQ(again.indices, cleaned.indices) << "round " << round;
    cuts += report.nonmanifold_edges;
    copies += report.split_vertex_copies;
  }
  EXPECT_LT(empty, 10u);
  EXPECT_GT(cuts, 100u) << "the soups should exercise the repairs";
  EXPECT_GT(copies, 100u);
}

TEST(Clean, BadInputIsAnError) {
  Mesh collinear = triangle_mesh({0, 0, 0, 1, 0, 0, 2, 0, 0}, {0, 1, 2});
  EXPECT_THROW(clean_mesh(collinear), Error);
  Mesh out_of_range = triangle_mesh({0, 0, 0, 1, 0, 0, 0, 1, 0}, {0, 1, 3});
  EXPECT_THROW(clean_mesh(out_of_range), Error);
  Mesh ragged = triangle_mesh({0, 0, 0, 1, 0, 0, 0, 1, 0}, {0, 1});
  EXPECT_THROW(clean_mesh(ragged), Error);
  Mesh short_colors = triangle_mesh({0, 0, 0, 1, 0, 0, 0, 1, 0}, {0, 1, 2});
  short_colors.colors = {1, 2, 3, 4};
  EXPECT_THROW(clean_mesh(short_colors), Error);
}

TEST(Clean, RealScansComeOutManifold) {
  PMS_REQUIRE_SHARED_MODEL(path, "bunny_res2.ply.xz");  // Stanford's decimation: duplicates, non-manifold edges
  Mesh mesh = load_mesh(path.string());
  tag_vertices(mesh);
  const Mesh input = mesh;
  const CleanReport report = clean_mesh(mesh);
  std::string why;
  EXPECT_TRUE(is_oriented_manifold(mesh, &why)) << why;
  EXPECT_EQ(report.duplicate_faces, 87u);
  EXPECT_GT(report.nonmanifold_edges, 0u);
  expect_attributes_in_step(input, mesh);
}

}  // namespace
}  // namespace pms
