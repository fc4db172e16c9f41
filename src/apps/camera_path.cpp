#include "apps/camera_path.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "common/error.h"
#include "spm/hierarchy.h"

namespace pms::app {
namespace {

constexpr float kPi = std::numbers::pi_v<float>;
constexpr float kDegree = kPi / 180;

struct Frame3 {
  float centre[3], extent[3];
  float radius = 0, diagonal = 0;
  int up = 1, e1 = 2, e2 = 0;  // up axis and a right-handed horizontal pair: e1 x e2 = up
};

Frame3 frame_of(const ModelData& model) {
  Frame3 f;
  float diag2 = 0;
  for (int k = 0; k < 3; ++k) {
    f.centre[k] = 0.5f * (model.bbox_min[k] + model.bbox_max[k]);
    f.extent[k] = model.bbox_max[k] - model.bbox_min[k];
    diag2 += f.extent[k] * f.extent[k];
  }
  f.diagonal = std::sqrt(diag2);
  if (!(f.diagonal > 0) || !std::isfinite(f.diagonal)) fail("model", "empty or invalid bounding box");
  f.radius = 0.5f * f.diagonal;
  int order[3] = {0, 1, 2};
  std::sort(order, order + 3, [&](int a, int b) { return f.extent[a] < f.extent[b]; });
  if (f.extent[order[0]] < 0.5f * f.extent[order[1]]) f.up = order[0];
  f.e1 = (f.up + 1) % 3;  // cyclic, so e1 x e2 = up: y up -> (z, x), z up -> (x, y), x up -> (y, z)
  f.e2 = (f.up + 2) % 3;
  return f;
}

// A unit direction at azimuth `theta` (from e1 toward e2) and elevation `elevation`.
void direction(const Frame3& f, float theta, float elevation, float out[3]) {
  out[0] = out[1] = out[2] = 0;
  out[f.e1] = std::cos(elevation) * std::cos(theta);
  out[f.e2] = std::cos(elevation) * std::sin(theta);
  out[f.up] = std::sin(elevation);
}

Camera camera_at(const PathOptions& options, const Frame3& f, const float eye[3], const float target[3]) {
  Camera c;
  for (int k = 0; k < 3; ++k) {
    c.eye[k] = eye[k];
    c.target[k] = target[k];
    c.up[k] = k == f.up ? 1.0f : 0.0f;
  }
  c.fovy_deg = options.fovy_deg;
  c.width = options.width;
  c.height = options.height;
  return c;
}

// Distance at which the bounding sphere just fits the narrower of the two fields of view.
float framing_distance(const PathOptions& options, const Frame3& f) {
  const float half_y = 0.5f * options.fovy_deg * kDegree;
  const float half_x = std::atan(std::tan(half_y) * float(options.width) / float(options.height));
  return f.radius / std::sin(std::min(half_x, half_y));
}

float parameter(uint32_t i, uint32_t frames) { return frames > 1 ? float(i) / float(frames - 1) : 0.0f; }

std::vector<Camera> orbit(const ModelData&, const PathOptions& options, const Frame3& f) {
  const float distance = framing_distance(options, f);
  std::vector<Camera> path;
  for (uint32_t i = 0; i < options.frames; ++i) {
    float dir[3], eye[3];
    direction(f, 2 * kPi * float(i) / float(options.frames), 20 * kDegree, dir);
    for (int k = 0; k < 3; ++k) eye[k] = f.centre[k] + distance * dir[k];
    path.push_back(camera_at(options, f, eye, f.centre));
  }
  return path;
}

// kim-lee-kobbelt 2005 §8, Fig. 5: "looks around the model from top to bottom".
std::vector<Camera> look(const PathOptions& options, const Frame3& f) {
  const float distance = framing_distance(options, f);
  std::vector<Camera> path;
  for (uint32_t i = 0; i < options.frames; ++i) {
    float dir[3], eye[3];
    const float elevation = (60 - 120 * parameter(i, options.frames)) * kDegree;
    direction(f, 2 * kPi * float(i) / float(options.frames), elevation, dir);
    for (int k = 0; k < 3; ++k) eye[k] = f.centre[k] + distance * dir[k];
    path.push_back(camera_at(options, f, eye, f.centre));
  }
  return path;
}

// The support distance of the box from its centre along the horizontal direction `dir`.
float horizontal_support(const Frame3& f, const float dir[3]) {
  return 0.5f * (std::abs(dir[f.e1]) * f.extent[f.e1] + std::abs(dir[f.e2]) * f.extent[f.e2]);
}

std::vector<Camera> scan(const ModelData& model, const PathOptions& options, const Frame3& f) {
  const float height = f.extent[f.up];
  const float reach = height / (6 * std::tan(0.5f * options.fovy_deg * kDegree));  // a third of the height in view
  std::vector<Camera> path;
  for (uint32_t i = 0; i < options.frames; ++i) {
    const float t = parameter(i, options.frames);
    const float theta = (-30 + 60 * t) * kDegree;
    float dir[3], eye[3], target[3];
    direction(f, theta, 0, dir);
    // Just outside the box along `dir`: its support distance from the centre, plus the reach.
    const float support = horizontal_support(f, dir);
    for (int k = 0; k < 3; ++k) target[k] = f.centre[k];
    target[f.up] = model.bbox_min[f.up] + t * height;
    for (int k = 0; k < 3; ++k) eye[k] = target[k] + (support + reach) * dir[k];
    path.push_back(camera_at(options, f, eye, target));
  }
  return path;
}

// zheng-chan 2006 §6's second route: in from the orbit's distance to the scan's (geometric, over the first
// third) while turning about the vertical axis through the centre, the angular speed growing linearly from
// zero, so the last frames turn fastest: two turns in all.
std::vector<Camera> rotate(const ModelData&, const PathOptions& options, const Frame3& f) {
  const float height = f.extent[f.up];
  const float reach = height / (6 * std::tan(0.5f * options.fovy_deg * kDegree));
  const float far = framing_distance(options, f);
  std::vector<Camera> path;
  for (uint32_t i = 0; i < options.frames; ++i) {
    const float t = parameter(i, options.frames);
    float dir[3], eye[3];
    direction(f, 4 * kPi * t * t, 10 * kDegree, dir);
    const float near = std::min(far, horizontal_support(f, dir) + reach);
    const float distance = far * std::pow(near / far, std::min(1.0f, 3 * t));
    for (int k = 0; k < 3; ++k) eye[k] = f.centre[k] + distance * dir[k];
    path.push_back(camera_at(options, f, eye, f.centre));
  }
  return path;
}

std::vector<Camera> zoom(const ModelData& model, const PathOptions& options, const Frame3& f) {
  float dir[3];
  direction(f, 30 * kDegree, 20 * kDegree, dir);
  // The surface point seen head-on from there: the vertex farthest out along the direction (on the
  // convex hull, so the close-up camera stays outside the model).
  const float* point = f.centre;
  float best = -INFINITY;
  for (size_t n = 0; n + 2 < model.position.size(); n += 3) {
    const float* p = &model.position[n];
    const float along = (p[0] - f.centre[0]) * dir[0] + (p[1] - f.centre[1]) * dir[1] + (p[2] - f.centre[2]) * dir[2];
    if (along > best) {
      best = along;
      point = p;
    }
  }
  const float far = 6 * framing_distance(options, f), near = 0.02f * f.diagonal;
  std::vector<Camera> path;
  for (uint32_t i = 0; i < options.frames; ++i) {
    const float t = parameter(i, options.frames);
    const float distance = far * std::pow(near / far, t);
    const float w = (far - distance) / (far - near);  // the target slides as the distance shrinks
    float eye[3], target[3];
    for (int k = 0; k < 3; ++k) {
      target[k] = f.centre[k] + w * (point[k] - f.centre[k]);
      eye[k] = target[k] + distance * dir[k];
    }
    path.push_back(camera_at(options, f, eye, target));
  }
  return path;
}

}  // namespace

PathKind parse_path_kind(const std::string& name) {
  if (name == "orbit") return PathKind::orbit;
  if (name == "scan") return PathKind::scan;
  if (name == "zoom") return PathKind::zoom;
  if (name == "look") return PathKind::look;
  if (name == "rotate") return PathKind::rotate;
  fail("path", "unknown kind \"" + name + "\" (expected orbit, scan, zoom, look or rotate)");
}

std::vector<Camera> make_camera_path(PathKind kind, const ModelData& model, const PathOptions& options) {
  if (options.frames == 0 || options.frames > 1000000) fail("path", "--frames must be in [1, 1000000]");
  if (!(options.fovy_deg > 0 && options.fovy_deg < 180)) fail("path", "--fovy must be in (0, 180) degrees");
  if (options.width == 0 || options.height == 0 || options.width > 16384 || options.height > 16384)
    fail("path", "--width and --height must be in [1, 16384]");
  if (!model.bbox_min || !model.bbox_max) fail("model", "no bounding box");
  const Frame3 f = frame_of(model);
  switch (kind) {
    case PathKind::orbit:
      return orbit(model, options, f);
    case PathKind::scan:
      return scan(model, options, f);
    case PathKind::zoom:
      return zoom(model, options, f);
    case PathKind::look:
      return look(options, f);
    case PathKind::rotate:
      return rotate(model, options, f);
  }
  fail("path", "unknown kind");
}

}  // namespace pms::app
