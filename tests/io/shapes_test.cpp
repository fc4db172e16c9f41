// Generated shapes: oriented manifolds with the right topology and orientation; the terrain is
// deterministic, near its target size and has real relief.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>
#include <vector>

#include "common/error.h"
#include "io/manifold_check.h"
#include "io/mesh.h"
#include "io/shapes.h"

namespace pms {
namespace {

// Undirected edges with how many faces use each.
std::vector<std::pair<std::pair<uint32_t, uint32_t>, int>> edge_uses(const Mesh& m) {
  std::vector<std::pair<uint32_t, uint32_t>> edges;
  for (size_t c = 0; c < m.indices.size(); ++c) {
    const uint32_t a = m.indices[c], b = m.indices[c % 3 == 2 ? c - 2 : c + 1];
    edges.push_back(std::minmax(a, b));
  }
  std::sort(edges.begin(), edges.end());
  std::vector<std::pair<std::pair<uint32_t, uint32_t>, int>> uses;
  for (const auto& e : edges)
    if (!uses.empty() && uses.back().first == e) ++uses.back().second;
    else uses.push_back({e, 1});
  return uses;
}

long euler_characteristic(const Mesh& m) {
  return long(m.vertex_count()) - long(edge_uses(m).size()) + long(m.face_count());
}

size_t boundary_edges(const Mesh& m) {
  const auto uses = edge_uses(m);
  return size_t(std::count_if(uses.begin(), uses.end(), [](const auto& e) { return e.second == 1; }));
}

std::array<float, 3> point(const Mesh& m, uint32_t v) {
  return {m.positions[3 * size_t(v)], m.positions[3 * size_t(v) + 1], m.positions[3 * size_t(v) + 2]};
}

// (b - a) x (c - a) and the centroid of face f.
std::array<float, 3> face_normal(const Mesh& m, size_t f) {
  const auto a = point(m, m.indices[3 * f]), b = point(m, m.indices[3 * f + 1]), c = point(m, m.indices[3 * f + 2]);
  const float u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  return {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
}

std::array<float, 3> face_centroid(const Mesh& m, size_t f) {
  std::array<float, 3> s{};
  for (int k = 0; k < 3; ++k)
    for (int i = 0; i < 3; ++i) s[i] += point(m, m.indices[3 * f + k])[i] / 3;
  return s;
}

TEST(Shapes, SphereIsAClosedOutwardGenusZeroManifold) {
  const Mesh sphere = make_sphere(12, 16);
  std::string why;
  EXPECT_TRUE(is_oriented_manifold(sphere, &why)) << why;
  EXPECT_EQ(sphere.vertex_count(), 11u * 16u + 2u);  // one vertex per pole
  EXPECT_EQ(euler_characteristic(sphere), 2);
  EXPECT_EQ(boundary_edges(sphere), 0u);
  for (size_t f = 0; f < sphere.face_count(); ++f) {
    const auto n = face_normal(sphere, f), c = face_centroid(sphere, f);
    EXPECT_GT(n[0] * c[0] + n[1] * c[1] + n[2] * c[2], 0.0f) << "face " << f << " points inward";
  }
}

TEST(Shapes, TorusIsAClosedOutwardGenusOneManifold) {
  const float R = 1, r = 0.3f;
  const Mesh torus = make_torus(20, 10, R, r);
  std::string why;
  EXPECT_TRUE(is_oriented_manifold(torus, &why)) << why;
  EXPECT_EQ(euler_characteristic(torus), 0);
  EXPECT_EQ(boundary_edges(torus), 0u);
  for (size_t f = 0; f < torus.face_count(); ++f) {
    const auto n = face_normal(torus, f), c = face_centroid(torus, f);
    const float ring = std::hypot(c[0], c[1]);  // away from the nearest point of the tube's centre circle
    const float out[3] = {c[0] - R * c[0] / ring, c[1] - R * c[1] / ring, c[2]};
    EXPECT_GT(n[0] * out[0] + n[1] * out[1] + n[2] * out[2], 0.0f) << "face " << f << " points inward";
  }
}

TEST(Shapes, GridIsAnUpwardDiskWithOneBoundaryLoop) {
  const int nx = 9, ny = 7;
  const Mesh grid = make_grid(nx, ny);
  std::string why;
  EXPECT_TRUE(is_oriented_manifold(grid, &why)) << why;
  EXPECT_EQ(grid.face_count(), size_t(2 * nx * ny));
  EXPECT_EQ(euler_characteristic(grid), 1);
  EXPECT_EQ(boundary_edges(grid), size_t(2 * (nx + ny)));
  for (size_t f = 0; f < grid.face_count(); ++f) EXPECT_GT(face_normal(grid, f)[2], 0.0f) << "face " << f;
  float lowest = 0, highest = 0;
  for (size_t v = 0; v < grid.vertex_count(); ++v) {
    lowest = std::min(lowest, point(grid, uint32_t(v))[2]);
    highest = std::max(highest, point(grid, uint32_t(v))[2]);
  }
  EXPECT_GT(highest - lowest, 0.01f) << "the grid should not be flat";
}

TEST(Shapes, NonManifoldFixtureIsNotAManifold) {
  const Mesh fixture = make_nonmanifold_fixture();
  EXPECT_FALSE(is_oriented_manifold(fixture));
}

TEST(Shapes, TerrainIsNearTheTargetAndDeterministic) {
  for (uint64_t target : {5000u, 100000u, 123457u}) {
    const Mesh a = make_terrain(target, 3), b = make_terrain(target, 3);
    EXPECT_NEAR(double(a.face_count()), double(target), 0.01 * double(target));
    EXPECT_EQ(a.positions, b.positions);
    EXPECT_EQ(a.indices, b.indices);
  }
  EXPECT_NE(make_terrain(5000, 3).positions, make_terrain(5000, 4).positions);
}

TEST(Shapes, TerrainIsAnUpwardDiskWithMountainsAndValleys) {
  const Mesh t = make_terrain(200000, 1);
  std::string why;
  EXPECT_TRUE(is_oriented_manifold(t, &why)) << why;
  EXPECT_EQ(euler_characteristic(t), 1);
  for (size_t f = 0; f < t.face_count(); ++f) ASSERT_GT(face_normal(t, f)[2], 0.0f) << "face " << f;
  std::array<float, 3> lo = point(t, 0), hi = lo;
  for (size_t v = 0; v < t.vertex_count(); ++v)
    for (int i = 0; i < 3; ++i) {
      lo[i] = std::min(lo[i], point(t, uint32_t(v))[i]);
      hi[i] = std::max(hi[i], point(t, uint32_t(v))[i]);
    }
  EXPECT_FLOAT_EQ(hi[0] - lo[0], 10000.0f);  // 10 km across
  EXPECT_NEAR(hi[1] - lo[1], 10000.0f, 100.0f);
  EXPECT_GT(hi[2] - lo[2], 1000.0f) << "mountains";
  EXPECT_LT(hi[2], 2000.0f);
  // Relief at every scale: some cells are steep (ridges), some nearly level (valley floors).
  size_t steep = 0, level = 0;
  for (size_t f = 0; f < t.face_count(); ++f) {
    const auto n = face_normal(t, f);
    const float slope = std::hypot(n[0], n[1]) / n[2];
    steep += slope > 1.0f;
    level += slope < 0.05f;
  }
  EXPECT_GT(steep, t.face_count() / 100);
  EXPECT_GT(level, t.face_count() / 100);
}

// Heights are a function of the ground position alone: a terrain with twice the cells per side (built
// on two threads) holds the coarser one's vertices bit for bit (built on one).
TEST(Shapes, TerrainHeightsDoNotDependOnResolutionOrThreads) {
  const Mesh coarse = make_terrain(2 * 40 * 40), fine = make_terrain(2 * 80 * 80);
  ASSERT_EQ(coarse.vertex_count(), 41u * 41u);
  ASSERT_EQ(fine.vertex_count(), 81u * 81u);
  for (uint32_t y = 0; y <= 40; ++y)
    for (uint32_t x = 0; x <= 40; ++x)
      ASSERT_EQ(point(coarse, y * 41 + x), point(fine, 2 * y * 81 + 2 * x)) << x << ", " << y;
}

// The coloured terrain is today's terrain (same positions, same faces, bit for bit) with land colours:
// every class of land shows, the same call gives the same bytes, and the plain terrain stays uncoloured.
TEST(Shapes, ColouredTerrainIsThePlainTerrainWithLandColours) {
  const Mesh plain = make_terrain(100000, 1), colored = make_terrain(100000, 1, TerrainColors::land);
  EXPECT_FALSE(plain.has_colors());
  EXPECT_EQ(colored.positions, plain.positions);
  EXPECT_EQ(colored.indices, plain.indices);
  ASSERT_EQ(colored.colors.size(), 4 * colored.vertex_count());
  EXPECT_EQ(make_terrain(100000, 1, TerrainColors::land).colors, colored.colors);
  size_t water = 0, grass = 0, rock = 0, snow = 0;
  for (size_t v = 0; v < colored.vertex_count(); ++v) {
    const int r = colored.colors[4 * v], g = colored.colors[4 * v + 1], b = colored.colors[4 * v + 2];
    ASSERT_EQ(colored.colors[4 * v + 3], 255) << "opaque";
    const float height = point(colored, uint32_t(v))[2];
    if (b > r + 40 && b > g) {
      ++water;
      EXPECT_LT(height, 60.0f) << "water only on the valley floors, vertex " << v;
    }
    grass += g > r + 15 && g > b + 15;
    rock += std::abs(r - g) < 20 && std::abs(g - b) < 20 && r > 90 && r < 160;
    if (r > 220 && g > 220 && b > 220) {
      ++snow;
      EXPECT_GT(height, 900.0f) << "snow only high up, vertex " << v;
    }
  }
  const size_t some = colored.vertex_count() / 200;
  EXPECT_GT(water, some);
  EXPECT_GT(grass, 10 * some);
  EXPECT_GT(rock, some);
  EXPECT_GT(snow, some);
}

TEST(Shapes, TerrainRefusesAnUnboundedSize) { EXPECT_THROW(make_terrain(uint64_t(1) << 40), Error); }

}  // namespace
}  // namespace pms
