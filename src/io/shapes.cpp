// Generated meshes: closed and open test shapes, a non-manifold fixture, and the demo terrain.
// The terrain uses only integer hashing and + - * / floor on floats, so the same arguments give the same
// mesh bit for bit on every IEEE machine and for any thread count.
#include "io/shapes.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <thread>

#include "common/error.h"
#include "io/terrain_colors.h"

namespace pms {
namespace {

constexpr float kPi = std::numbers::pi_v<float>;

// Generated sizes are bounded like loaded ones: 32-bit vertex ids.
void check_vertex_count(const std::string& shape, uint64_t vertices) {
  if (vertices >= UINT32_MAX) fail(shape, "too many vertices for 32-bit indices");
}

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
void quad_faces(uint32_t* out, uint32_t a, uint32_t b, uint32_t c, uint32_t d, bool flip) {
  const uint32_t faces[2][6] = {{a, b, c, a, c, d}, {a, b, d, b, c, d}};
  std::copy_n(faces[flip], 6, out);
}

void add_quad(Mesh& m, uint32_t a, uint32_t b, uint32_t c, uint32_t d, bool flip) {
  m.indices.resize(m.indices.size() + 6);
  quad_faces(&m.indices[m.indices.size() - 6], a, b, c, d, flip);
}

// ---- Terrain noise ------------------------------------------------------------------------------------

uint32_t hash(uint32_t x, uint32_t y, uint32_t seed) {
  uint32_t h = x * 0x8da6b343u ^ y * 0xd8163841u ^ seed * 0xcb1ab31fu;
  h ^= h >> 16;
  h *= 0x7feb352du;
  h ^= h >> 15;
  h *= 0x846ca68bu;
  h ^= h >> 16;
  return h;
}

// Gradient noise (Perlin 2002: quintic fade) with each lattice gradient one of 8 unit directions
// picked by the hash, so no trigonometry is involved. Result within [-1, 1].
float gradient_noise(float x, float y, uint32_t seed) {
  constexpr float d = 0.70710678f;
  constexpr float gx[8] = {1, d, 0, -d, -1, -d, 0, d}, gy[8] = {0, d, 1, d, 0, -d, -1, -d};
  const float fx = std::floor(x), fy = std::floor(y);
  const uint32_t ix = uint32_t(int32_t(fx)), iy = uint32_t(int32_t(fy));
  const float tx = x - fx, ty = y - fy;
  auto ramp = [&](uint32_t cx, uint32_t cy, float dx, float dy) {
    const uint32_t g = hash(cx, cy, seed) >> 29;
    return gx[g] * dx + gy[g] * dy;
  };
  auto fade = [](float t) { return t * t * t * (t * (t * 6 - 15) + 10); };
  const float u = fade(tx), v = fade(ty);
  const float a = ramp(ix, iy, tx, ty), b = ramp(ix + 1, iy, tx - 1, ty);
  const float c = ramp(ix, iy + 1, tx, ty - 1), e = ramp(ix + 1, iy + 1, tx - 1, ty - 1);
  const float bottom = a + (b - a) * u, top = c + (e - c) * u;
  return std::clamp((bottom + (top - bottom) * v) * 1.41421356f, -1.0f, 1.0f);
}

float smoothstep(float lo, float hi, float x) {
  const float t = std::clamp((x - lo) / (hi - lo), 0.0f, 1.0f);
  return t * t * (3 - 2 * t);
}

// Octave i samples the plane rotated by i * 36.87 degrees (a 3-4-5 rotation, exact in float) and
// shifted, so the lattices of successive octaves never line up into visible grid stripes.
struct Octave {
  float x, y;
  void next() {
    const float rx = 0.8f * x - 0.6f * y, ry = 0.6f * x + 0.8f * y;
    x = 2 * rx + 19.1f;
    y = 2 * ry + 7.3f;
  }
};

// Fractional Brownian motion: octaves of halving amplitude and doubling frequency, within [-1, 1].
float fbm(float x, float y, float wavelength, int octaves, uint32_t seed) {
  float sum = 0, amplitude = 1, total = 0;
  Octave p{x / wavelength, y / wavelength};
  for (int i = 0; i < octaves; ++i, p.next()) {
    sum += amplitude * gradient_noise(p.x, p.y, seed + uint32_t(i));
    total += amplitude;
    amplitude *= 0.5f;
  }
  return sum / total;
}

// Ridged multifractal (Musgrave, "Texturing & Modeling" ch. 16): sharp crests where the noise
// crosses zero, and fine detail only where the coarser octaves already made a crest. Within [0, 1].
float ridged(float x, float y, float wavelength, int octaves, uint32_t seed) {
  float sum = 0, amplitude = 1, total = 0, weight = 1;
  Octave p{x / wavelength, y / wavelength};
  for (int i = 0; i < octaves; ++i, p.next()) {
    const float crest = 1 - std::abs(gradient_noise(p.x, p.y, seed + uint32_t(i)));
    const float signal = crest * crest * weight;
    sum += amplitude * signal;
    total += amplitude;
    weight = std::min(1.0f, 2 * signal);
    amplitude *= 0.5f;
  }
  return sum / total;
}

// Height in metres over a 10 km square: rolling hills everywhere, ridged ranges where a slow mask is
// high, and winding valleys carved where another slow noise crosses zero. Detail reaches ~10 m.
float terrain_height(float x, float y, uint32_t seed) {
  const uint32_t s = seed * 64;  // each layer below takes its own block of octave seeds
  const float hills = 250 * (0.5f + 0.5f * fbm(x, y, 4000, 8, s));
  const float ranges = smoothstep(-0.35f, 0.35f, fbm(x, y, 6000, 2, s + 20));
  const float peaks = 1500 * ranges * ridged(x, y, 3000, 9, s + 30);
  // Domain warp so the valleys meander instead of following the noise lattice.
  const float wx = x + 600 * gradient_noise(x / 2000, y / 2000, s + 50);
  const float wy = y + 600 * gradient_noise(x / 2000 + 17.5f, y / 2000 + 3.25f, s + 51);
  const float valley = smoothstep(0.0f, 0.25f, std::abs(fbm(wx, wy, 4500, 2, s + 52)));
  return 20 + (hills + peaks) * (0.15f + 0.85f * valley);
}

}  // namespace

Mesh make_sphere(int rings, int segments) {
  rings = std::max(rings, 2);
  segments = std::max(segments, 3);
  check_vertex_count("sphere", uint64_t(rings - 1) * uint64_t(segments) + 2);
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
  auto ring_vertex = [&](int r, int s) {
    return uint32_t(1 + uint32_t(r - 1) * uint32_t(segments) + uint32_t(s % segments));
  };
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
  check_vertex_count("torus", uint64_t(rings) * uint64_t(segments));
  Mesh m;
  for (int i = 0; i < rings; ++i) {
    const float u = 2 * kPi * float(i) / float(rings);
    for (int j = 0; j < segments; ++j) {
      const float v = 2 * kPi * float(j) / float(segments);
      add_vertex(m, (R + r * std::cos(v)) * std::cos(u), (R + r * std::cos(v)) * std::sin(u), r * std::sin(v));
    }
  }
  auto at = [&](int i, int j) { return uint32_t(i % rings) * uint32_t(segments) + uint32_t(j % segments); };
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < segments; ++j) add_quad(m, at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1), false);
  return m;
}

Mesh make_grid(int nx, int ny) {
  nx = std::max(nx, 1);
  ny = std::max(ny, 1);
  check_vertex_count("grid", uint64_t(nx + 1) * uint64_t(ny + 1));
  Mesh m;
  for (int y = 0; y <= ny; ++y)
    for (int x = 0; x <= nx; ++x) {
      const float fx = float(x) / float(nx), fy = float(y) / float(ny);
      add_vertex(m, fx, fy, 0.05f * std::sin(3 * fx) * std::cos(2 * fy));  // a gentle bump: not flat
    }
  auto at = [&](int x, int y) { return uint32_t(y) * uint32_t(nx + 1) + uint32_t(x); };
  for (int y = 0; y < ny; ++y)
    for (int x = 0; x < nx; ++x) add_quad(m, at(x, y), at(x + 1, y), at(x + 1, y + 1), at(x, y + 1), (x + y) % 2 == 1);
  return m;
}

// What clean_mesh() meets in this fixture, in input order (tests/io/clean_test.cpp counts each):
// two tetrahedra sharing vertex 0; a book of three faces on edge 7-8; a reversed duplicate of a face;
// a face with a repeated corner and a zero-area one; a coincident copy of vertex 3 (12) in a face that
// gives edge 1-3 a third face; two faces glued along 15-17 with opposite orientations; an unused vertex.
Mesh make_nonmanifold_fixture() {
  Mesh m;
  const float p[][3] = {{0, 0, 0}, {1, 0, 0},  {0, 1, 0},  {0, 0, 1},  {-1, 0, 0}, {0, -1, 0}, {0, 0, -1},
                        {3, 0, 0}, {3, 1, 0},  {4, 0, 0},  {2, 0, 0},  {3, 0, 1},  {0, 0, 1},  {1, 1, 1},
                        {9, 9, 9}, {10, 0, 0}, {11, 0, 0}, {11, 1, 0}, {10, 1, 0}};
  for (const auto& v : p) add_vertex(m, v[0], v[1], v[2]);
  const uint32_t faces[][3] = {{0, 2, 1},    {0, 1, 3},   {0, 3, 2},  {1, 2, 3},  // tetrahedron in the positive octant
                               {0, 4, 5},    {0, 6, 4},   {0, 5, 6},  {4, 6, 5},  // tetrahedron in the negative octant
                               {7, 8, 9},    {8, 7, 10},  {7, 8, 11},             // book
                               {3, 2, 1},    {1, 1, 2},   {7, 9, 10},  // duplicate, repeated corner, collinear
                               {12, 1, 13},                            // welds to (3, 1, 13)
                               {15, 16, 17}, {15, 18, 17}};            // the second one runs 17->15 like the first
  for (const auto& f : faces) add_face(m, f[0], f[1], f[2]);
  return m;
}

Mesh make_terrain(uint64_t target_faces, uint32_t seed, TerrainColors colors) {
  constexpr uint64_t kMaxFaces = uint64_t(1) << 31;
  const std::string name = "terrain:" + std::to_string(target_faces);
  if (target_faces > kMaxFaces) fail(name, "at most " + std::to_string(kMaxFaces) + " faces");
  // nx * ny cells, two faces each, as near the target as whole rows allow; square cells 10 km / nx wide.
  const uint32_t nx = uint32_t(std::max<int64_t>(1, std::llround(std::sqrt(double(target_faces) / 2))));
  const uint32_t ny = uint32_t(std::max<uint64_t>(1, (target_faces + nx) / (2 * uint64_t(nx))));
  check_vertex_count(name, uint64_t(nx + 1) * (ny + 1));
  const float spacing = 10000.0f / float(nx);
  Mesh m;
  m.positions.resize(3 * size_t(nx + 1) * (ny + 1));
  m.indices.resize(6 * size_t(nx) * ny);
  // Heights dominate the cost: rows are split between two threads. Each vertex depends only on its own
  // grid coordinates, so the split cannot change a bit.
  auto fill_rows = [&](uint32_t y0, uint32_t y1) {
    for (uint32_t y = y0; y < y1; ++y)
      for (uint32_t x = 0; x <= nx; ++x) {
        float* v = &m.positions[3 * (size_t(y) * (nx + 1) + x)];
        v[0] = float(x) * spacing;
        v[1] = float(y) * spacing;
        v[2] = terrain_height(v[0], v[1], seed);
      }
  };
  const uint32_t rows = ny + 1, half = rows / 2;
  std::thread helper;
  if (rows > 64) helper = std::thread(fill_rows, half, rows);
  fill_rows(0, helper.joinable() ? half : rows);
  auto at = [&](uint32_t x, uint32_t y) { return y * (nx + 1) + x; };
  for (uint32_t y = 0; y < ny; ++y)
    for (uint32_t x = 0; x < nx; ++x)  // alternating diagonals, counter-clockwise seen from +z
      quad_faces(&m.indices[6 * (size_t(y) * nx + x)], at(x, y), at(x + 1, y), at(x + 1, y + 1), at(x, y + 1),
                 (x + y) % 2 == 1);
  if (helper.joinable()) helper.join();
  if (colors == TerrainColors::land) color_land(m, nx + 1, ny + 1, spacing);
  return m;
}

}  // namespace pms
