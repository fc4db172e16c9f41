// Tiny scenes with a projection simple enough to work out by hand.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "common/camera.h"
#include "render/render.h"

namespace pms::test {

// Eye at (0, 0, 1) looking down -z, fovy 90 degrees, square viewport n x n: a point (x, y, 0) lands on
// screen at ((x + 1) * n / 2, (1 - y) * n / 2) pixels (row 0 at the top).
inline ViewParams square_view(uint32_t n) {
  Camera camera;
  camera.eye[0] = 0, camera.eye[1] = 0, camera.eye[2] = 1;
  camera.target[0] = 0, camera.target[1] = 0, camera.target[2] = 0;
  camera.up[0] = 0, camera.up[1] = 1, camera.up[2] = 0;
  camera.fovy_deg = 90;
  camera.width = camera.height = n;
  const float lo[3] = {-1, -1, -0.5f}, hi[3] = {1, 1, 0.5f};
  return make_view(camera, lo, hi);
}

// World point of the screen position (sx, sy) of square_view(n), on the plane z = 0.
inline void screen_to_world(float sx, float sy, uint32_t n, float out[3]) {
  out[0] = sx * 2.0f / float(n) - 1.0f;
  out[1] = 1.0f - sy * 2.0f / float(n);
  out[2] = 0;
}

// A mesh built from screen-space triangles of square_view(n) at z = 0.
struct ScreenMesh {
  std::vector<float> positions;
  std::vector<uint32_t> indices;
  std::vector<uint8_t> colors;

  uint32_t add_vertex(float sx, float sy, uint32_t n) {
    float p[3];
    screen_to_world(sx, sy, n, p);
    positions.insert(positions.end(), p, p + 3);
    return uint32_t(positions.size() / 3 - 1);
  }
  void add_triangle(uint32_t a, uint32_t b, uint32_t c) { indices.insert(indices.end(), {a, b, c}); }
  RenderMesh mesh() const { return {positions, indices, colors}; }
};

inline size_t count_face(const Image& image, uint32_t face) {
  size_t count = 0;
  for (const uint32_t id : image.face_id) count += id == face;
  return count;
}

}  // namespace pms::test

namespace pms::test {

// Ray through the centre of pixel (px, py) of `camera`, in double precision (the reference the
// rasterizer is checked against): direction = forward + ndc_x * aspect * tan * side + ndc_y * tan * up.
// (px, py) in pixels: the centre of pixel (i, j) is (i + 0.5, j + 0.5).
inline void pixel_ray(const Camera& camera, double px, double py, double dir[3]) {
  double f[3], up[3] = {camera.up[0], camera.up[1], camera.up[2]};
  for (int k = 0; k < 3; ++k) f[k] = double(camera.target[k]) - camera.eye[k];
  auto normalize = [](double v[3]) {
    const double l = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    for (int k = 0; k < 3; ++k) v[k] /= l;
  };
  auto cross = [](const double a[3], const double b[3], double out[3]) {
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
  };
  normalize(f);
  double s[3], u[3];
  cross(f, up, s);
  normalize(s);
  cross(s, f, u);
  const double tan_half = std::tan(double(camera.fovy_deg) * M_PI / 360.0);
  const double aspect = double(camera.width) / double(camera.height);
  const double ndc_x = px / camera.width * 2.0 - 1.0, ndc_y = 1.0 - py / camera.height * 2.0;
  for (int k = 0; k < 3; ++k) dir[k] = f[k] + ndc_x * aspect * tan_half * s[k] + ndc_y * tan_half * u[k];
}

// Intersection of the ray eye + t * dir (t > 0) with triangle (a, b, c): 1 = hit (barycentrics and t
// set), -1 = missed, 0 = within `margin` (barycentric units) of an edge, too close to call.
inline int ray_triangle(const float eye[3], const double dir[3], const float* a, const float* b, const float* c,
                        double margin, double bary[3], double& t) {
  double e1[3], e2[3], s[3], p[3], q[3];
  for (int k = 0; k < 3; ++k) {
    e1[k] = double(b[k]) - a[k];
    e2[k] = double(c[k]) - a[k];
    s[k] = double(eye[k]) - a[k];
  }
  p[0] = dir[1] * e2[2] - dir[2] * e2[1];
  p[1] = dir[2] * e2[0] - dir[0] * e2[2];
  p[2] = dir[0] * e2[1] - dir[1] * e2[0];
  const double det = e1[0] * p[0] + e1[1] * p[1] + e1[2] * p[2];
  if (std::fabs(det) < 1e-12) return 0;
  const double u = (s[0] * p[0] + s[1] * p[1] + s[2] * p[2]) / det;
  q[0] = s[1] * e1[2] - s[2] * e1[1];
  q[1] = s[2] * e1[0] - s[0] * e1[2];
  q[2] = s[0] * e1[1] - s[1] * e1[0];
  const double v = (dir[0] * q[0] + dir[1] * q[1] + dir[2] * q[2]) / det;
  t = (e2[0] * q[0] + e2[1] * q[1] + e2[2] * q[2]) / det;
  bary[0] = 1 - u - v, bary[1] = u, bary[2] = v;
  const double lowest = std::min(bary[0], std::min(bary[1], bary[2]));
  if (t <= 0 || lowest < -margin) return -1;  // clearly missed
  if (lowest < margin) return 0;              // too close to an edge to call
  return 1;
}

// What one pixel centre's ray meets on the triangle of positions[0, 9), as ray_triangle says.
struct PixelRay {
  uint32_t x = 0, y = 0;
  size_t pixel = 0;  // y * width + x
  int hit = 0;       // ray_triangle: 1 hit, -1 missed, 0 too close to an edge to call
  double bary[3] = {0, 0, 0}, t = 0;
};

// Casts every pixel centre's ray of `camera` at that triangle, row by row, and calls visit(ray).
template <class Visit>
void for_each_pixel_ray(const Camera& camera, const std::vector<float>& positions, double margin, Visit visit) {
  for (uint32_t y = 0; y < camera.height; ++y)
    for (uint32_t x = 0; x < camera.width; ++x) {
      PixelRay ray;
      ray.x = x, ray.y = y, ray.pixel = size_t(y) * camera.width + x;
      double dir[3];
      pixel_ray(camera, x + 0.5, y + 0.5, dir);
      ray.hit = ray_triangle(camera.eye, dir, &positions[0], &positions[3], &positions[6], margin, ray.bary, ray.t);
      visit(ray);
    }
}

}  // namespace pms::test
