// Camera -> view and projection transforms and frustum planes (gluLookAt / gluPerspective conventions).
#include "common/camera.h"

#include <algorithm>
#include <cmath>

#include "common/error.h"
#include "common/portable_math.h"

namespace pms {

namespace {

// One frame on: the eye one step further, the direction turned on as far again (linearly, renormalised).
std::optional<Camera> step_on(const Camera& a, const Camera& b) {
  float da[3], db[3];
  for (int i = 0; i < 3; ++i) {
    da[i] = a.target[i] - a.eye[i];
    db[i] = b.target[i] - b.eye[i];
  }
  const float la = std::sqrt(da[0] * da[0] + da[1] * da[1] + da[2] * da[2]);
  const float lb = std::sqrt(db[0] * db[0] + db[1] * db[1] + db[2] * db[2]);
  if (!(la > 0) || !(lb > 0)) return std::nullopt;
  float d[3];
  for (int i = 0; i < 3; ++i) d[i] = 2 * db[i] / lb - da[i] / la;
  const float ld = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  if (!(ld > 1e-6f)) return std::nullopt;
  Camera next = b;
  for (int i = 0; i < 3; ++i) {
    next.eye[i] = 2 * b.eye[i] - a.eye[i];
    next.target[i] = next.eye[i] + d[i] / ld * lb;
  }
  return next;
}

}  // namespace

std::optional<Camera> extrapolate(const Camera& a, const Camera& b, uint32_t steps) {
  Camera previous = a, next = b;
  for (uint32_t i = 0; i < steps; ++i) {
    const std::optional<Camera> on = step_on(previous, next);
    if (!on) return std::nullopt;
    previous = next;
    next = *on;
  }
  return next;
}

namespace {

void sub(const float a[3], const float b[3], float out[3]) {
  for (int i = 0; i < 3; ++i) out[i] = a[i] - b[i];
}
void cross(const float a[3], const float b[3], float out[3]) {
  out[0] = a[1] * b[2] - a[2] * b[1];
  out[1] = a[2] * b[0] - a[0] * b[2];
  out[2] = a[0] * b[1] - a[1] * b[0];
}
float dot(const float a[3], const float b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
bool normalize(float v[3]) {
  const float length = std::sqrt(dot(v, v));
  if (!(length > 1e-30f) || !std::isfinite(length)) return false;
  for (int i = 0; i < 3; ++i) v[i] /= length;
  return true;
}

// Depth range along the view direction that holds every corner of the box.
void depth_range(const ViewParams& view, const float box_min[3], const float box_max[3], float& near_plane,
                 float& far_plane) {
  float nearest = INFINITY, farthest = -INFINITY;
  for (int corner = 0; corner < 8; ++corner) {
    const float p[3] = {corner & 1 ? box_max[0] : box_min[0], corner & 2 ? box_max[1] : box_min[1],
                        corner & 4 ? box_max[2] : box_min[2]};
    float d[3];
    sub(p, view.eye, d);
    const float z = dot(d, view.forward);
    nearest = std::min(nearest, z);
    farthest = std::max(farthest, z);
  }
  // A little slack so faces on the box itself are not clipped by rounding.
  far_plane = std::max(farthest * 1.01f, 1e-6f);
  near_plane = std::max(nearest * 0.99f, far_plane * 1e-4f);
}

// Gribb-Hartmann: the planes are sums/differences of the clip matrix rows.
void extract_planes(ViewParams& view) {
  const float* m = view.view_projection.m;
  const int row_of_plane[6] = {0, 0, 1, 1, 2, 2};
  for (int i = 0; i < 6; ++i) {
    const float sign = i % 2 == 0 ? 1.0f : -1.0f;
    const int r = row_of_plane[i];
    float* plane = view.planes[i];
    for (int c = 0; c < 4; ++c) plane[c] = m[12 + c] + sign * m[4 * r + c];
    const float length = std::sqrt(plane[0] * plane[0] + plane[1] * plane[1] + plane[2] * plane[2]);
    for (int c = 0; c < 4; ++c) plane[c] /= length;
  }
}

// The view's unit forward and side axes, or what makes the camera unusable (nothing is written then).
const char* view_axes(const Camera& camera, float forward[3], float side[3]) {
  if (!(camera.fovy_deg > 0 && camera.fovy_deg < 180)) return "fovy_deg must be in (0, 180)";
  if (camera.width == 0 || camera.height == 0) return "viewport width and height must be positive";
  float f[3], s[3], up[3] = {camera.up[0], camera.up[1], camera.up[2]};
  sub(camera.target, camera.eye, f);
  if (!normalize(f)) return "eye and target must differ";
  cross(f, up, s);
  // |s| = |up| sin(angle): an up within about a microradian of the view (or zero) leaves the side axis to
  // rounding, and the view's basis with it.
  if (!(std::sqrt(dot(s, s)) > 1e-6f * std::sqrt(dot(up, up))) || !normalize(s))
    return "up must not be parallel to the view direction";
  for (int i = 0; i < 3; ++i) forward[i] = f[i], side[i] = s[i];
  return nullptr;
}

}  // namespace

const char* camera_problem(const Camera& camera) {
  float forward[3], side[3];
  return view_axes(camera, forward, side);
}

Mat4 multiply(const Mat4& a, const Mat4& b) {
  Mat4 out;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) {
      float sum = 0;
      for (int k = 0; k < 4; ++k) sum += a.m[4 * r + k] * b.m[4 * k + c];
      out.m[4 * r + c] = sum;
    }
  return out;
}

void transform_point(const Mat4& m, const float p[3], float clip[4]) {
  for (int r = 0; r < 4; ++r)
    clip[r] = m.m[4 * r] * p[0] + m.m[4 * r + 1] * p[1] + m.m[4 * r + 2] * p[2] + m.m[4 * r + 3];
}

ViewParams make_view(const Camera& camera, const float box_min[3], const float box_max[3]) {
  ViewParams view;
  view.camera = camera;
  float side[3], up[3];
  if (const char* problem = view_axes(camera, view.forward, side)) fail("camera", problem);
  for (int i = 0; i < 3; ++i) view.eye[i] = camera.eye[i];
  cross(side, view.forward, up);

  float* v = view.view.m;
  for (int c = 0; c < 3; ++c) {
    v[c] = side[c];
    v[4 + c] = up[c];
    v[8 + c] = -view.forward[c];
  }
  v[3] = -dot(side, view.eye);
  v[7] = -dot(up, view.eye);
  v[11] = dot(view.forward, view.eye);
  v[12] = v[13] = v[14] = 0;
  v[15] = 1;

  depth_range(view, box_min, box_max, view.near_plane, view.far_plane);
  const float n = view.near_plane, f = view.far_plane;
  // portable_tan: the server derives the same view from the camera the client sends, bit for bit.
  const float tan_half = portable_tan(camera.fovy_deg * float(M_PI) / 360.0f);
  const float aspect = float(camera.width) / float(camera.height);
  float* p = view.projection.m;
  std::fill(p, p + 16, 0.0f);
  p[0] = 1.0f / (aspect * tan_half);
  p[5] = 1.0f / tan_half;
  p[10] = -(f + n) / (f - n);
  p[11] = -2.0f * f * n / (f - n);
  p[14] = -1;

  view.view_projection = multiply(view.projection, view.view);
  extract_planes(view);
  view.pixel_angle = 2.0f * tan_half / float(camera.height);
  return view;
}

}  // namespace pms
