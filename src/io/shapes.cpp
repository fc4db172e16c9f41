// Generated meshes: closed and open test shapes, a non-manifold fixture, and the demo terrain.
// Everything is integer-hash based so the same arguments give the same mesh on every machine.
#include "io/shapes.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace pms {
namespace {

constexpr float kPi = std::numbers::pi_v<float>;

void add_vertex(Mesh& m, float x, float y, float z) {
  m.positions.push_back(x);
  m.positions.push_back(y);
  m.positions.push_back(z);
}

void add_face(Mesh& m, uint32_t a, uint32_t b, uint32_t c) {
  m.indices.push_back(a);
  m.indices.push_back(b);
  m.indices.push_back(c);
}

// Two triangles per cell (a b c d counter-clockwise); `flip` picks the other diagonal.
void add_quad(Mesh& m, uint32_t a, uint32_t b, uint32_t c, uint32_t d, bool flip) {
  if (flip) {
    add_face(m, a, b, d);
    add_face(m, b, c, d);
  } else {
    add_face(m, a, b, c);
    add_face(m, a, c, d);
  }
}

uint32_t hash(uint32_t x, uint32_t y, uint32_t seed) {
  uint32_t h = x * 0x8da6b343u ^ y * 0xd8163841u ^ seed * 0xcb1ab31fu;
  h ^= h >> 16;
  h *= 0x7feb352du;
  h ^= h >> 15;
  h *= 0x846ca68bu;
  h ^= h >> 16;
  return h;
}

// Value noise in [-1, 1] on an integer lattice, smoothly interpolated.
float value_noise(float x, float y, uint32_t seed) {
  const float fx = std::floor(x), fy = std::floor(y);
  const int32_t ix = int32_t(fx), iy = int32_t(fy);
  const float tx = x - fx, ty = y - fy;
  const float sx = tx * tx * (3 - 2 * tx), sy = ty * ty * (3 - 2 * ty);
  auto corner = [&](int32_t cx, int32_t cy) {
    return float(hash(uint32_t(cx), uint32_t(cy), seed) >> 8) * (2.0f / 16777215.0f) - 1.0f;
  };
  const float a = corner(ix, iy), b = corner(ix + 1, iy), c = corner(ix, iy + 1), d = corner(ix + 1, iy + 1);
  return (a + (b - a) * sx) + ((c + (d - c) * sx) - (a + (b - a) * sx)) * sy;
}

// Fractal height: rolling hills plus ridged mountains, in metres.
float terrain_height(float x, float y, uint32_t seed) {
  float hills = 0, amplitude = 1, frequency = 1.0f / 2500.0f;
  for (int octave = 0; octave < 6; ++octave) {
    hills += amplitude * value_noise(x * frequency, y * frequency, seed + octave);
    amplitude *= 0.5f;
    frequency *= 2.0f;
  }
  float ridges = 0;
  amplitude = 1;
  frequency = 1.0f / 4000.0f;
  for (int octave = 0; octave < 5; ++octave) {
    const float n = 1.0f - std::abs(value_noise(x * frequency, y * frequency, seed + 100 + octave));
    ridges += amplitude * n * n;
    amplitude *= 0.5f;
    frequency *= 2.1f;
  }
  const float mountains = std::max(0.0f, value_noise(x / 6000.0f, y / 6000.0f, seed + 200) + 0.2f);
  return 180.0f * hills + 900.0f * mountains * ridges;
}

}  // namespace

Mesh make_sphere(int rings, int segments) {
  rings = std::max(rings, 2);
  segments = std::max(segments, 3);
  Mesh m;
  add_vertex(m, 0, 0, 1);  // north pole
  for (int r = 1; r < rings; ++r) {
    const float theta = kPi * float(r) / float(rings);
    for (int s = 0; s < segments; ++s) {
      const float phi = 2 * kPi * float(s) / float(segments);
      add_vertex(m, std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
    }
  }
  const uint32_t south = uint32_t(m.vertex_count());
  add_vertex(m, 0, 0, -1);
  auto ring_vertex = [&](int r, int s) { return uint32_t(1 + (r - 1) * segments + (s % segments)); };
  for (int s = 0; s < segments; ++s) add_face(m, 0, ring_vertex(1, s), ring_vertex(1, s + 1));
  for (int r = 1; r + 1 < rings; ++r)
    for (int s = 0; s < segments; ++s)
      add_quad(m, ring_vertex(r, s), ring_vertex(r + 1, s), ring_vertex(r + 1, s + 1), ring_vertex(r, s + 1), false);
  for (int s = 0; s < segments; ++s) add_face(m, south, ring_vertex(rings - 1, s + 1), ring_vertex(rings - 1, s));
  return m;
}

Mesh make_torus(int rings, int segments, float R, float r) {
  rings = std::max(rings, 3);
  segments = std::max(segments, 3);
  Mesh m;
  for (int i = 0; i < rings; ++i) {
    const float u = 2 * kPi * float(i) / float(rings);
    for (int j = 0; j < segments; ++j) {
      const float v = 2 * kPi * float(j) / float(segments);
      add_vertex(m, (R + r * std::cos(v)) * std::cos(u), (R + r * std::cos(v)) * std::sin(u), r * std::sin(v));
    }
  }
  auto at = [&](int i, int j) { return uint32_t((i % rings) * segments + (j % segments)); };
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < segments; ++j) add_quad(m, at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1), false);
  return m;
}

Mesh make_grid(int nx, int ny) {
  nx = std::max(nx, 1);
  ny = std::max(ny, 1);
  Mesh m;
  for (int y = 0; y <= ny; ++y)
    for (int x = 0; x <= nx; ++x) {
      const float fx = float(x) / float(nx), fy = float(y) / float(ny);
      add_vertex(m, fx, fy, 0.05f * std::sin(3 * fx) * std::cos(2 * fy));
    }
  auto at = [&](int x, int y) { return uint32_t(y * (nx + 1) + x); };
  for (int y = 0; y < ny; ++y)
    for (int x = 0; x < nx; ++x) add_quad(m, at(x, y), at(x + 1, y), at(x + 1, y + 1), at(x, y + 1), (x + y) % 2 == 1);
  return m;
}

Mesh make_nonmanifold_fixture() {
  Mesh m;
  // Two tetrahedra touching at vertex 0 (a non-manifold vertex).
  add_vertex(m, 0, 0, 0);
  add_vertex(m, 1, 0, 0);
  add_vertex(m, 0, 1, 0);
  add_vertex(m, 0, 0, 1);
  add_vertex(m, -1, 0, 0);
  add_vertex(m, 0, -1, 0);
  add_vertex(m, 0, 0, -1);
  add_face(m, 0, 2, 1);
  add_face(m, 0, 1, 3);
  add_face(m, 0, 3, 2);
  add_face(m, 1, 2, 3);
  add_face(m, 0, 4, 5);
  add_face(m, 0, 6, 4);
  add_face(m, 0, 5, 6);
  add_face(m, 4, 6, 5);
  // A book of three triangles sharing edge (7, 8): a non-manifold edge.
  add_vertex(m, 3, 0, 0);
  add_vertex(m, 3, 1, 0);
  add_vertex(m, 4, 0, 0);
  add_vertex(m, 2, 0, 0);
  add_vertex(m, 3, 0, 1);
  add_face(m, 7, 8, 9);
  add_face(m, 8, 7, 10);
  add_face(m, 7, 8, 11);
  // A duplicate face and a degenerate one.
  add_face(m, 1, 2, 3);
  add_face(m, 1, 1, 2);
  // A coincident copy of vertex 3 used by an extra face of the first tetrahedron's neighbourhood.
  add_vertex(m, 0, 0, 1);
  add_vertex(m, 1, 1, 1);
  add_face(m, 12, 1, 13);
  return m;
}

Mesh make_terrain(uint64_t target_faces, uint32_t seed) {
  // cells^2 * 2 faces ~ target.
  const int cells = std::max(1, int(std::lround(std::sqrt(double(target_faces) / 2.0))));
  constexpr float kExtent = 10000.0f;  // 10 km square
  Mesh m;
  m.positions.reserve(3 * size_t(cells + 1) * size_t(cells + 1));
  m.indices.reserve(6 * size_t(cells) * size_t(cells));
  for (int y = 0; y <= cells; ++y)
    for (int x = 0; x <= cells; ++x) {
      const float px = kExtent * float(x) / float(cells), py = kExtent * float(y) / float(cells);
      add_vertex(m, px, py, terrain_height(px, py, seed));
    }
  auto at = [&](int x, int y) { return uint32_t(y * (cells + 1) + x); };
  for (int y = 0; y < cells; ++y)
    for (int x = 0; x < cells; ++x) add_quad(m, at(x, y), at(x + 1, y), at(x + 1, y + 1), at(x, y + 1), (x + y) % 2 == 1);
  return m;
}

}  // namespace pms
