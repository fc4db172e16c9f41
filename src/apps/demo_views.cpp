#include "apps/demo_views.h"

#include <algorithm>
#include <cmath>

#include "apps/camera_path.h"

namespace pms::app {
namespace {

// A flat model's axes: `up` the thinnest (-1 for a model that is not flat), `along` and `across` the others.
struct Axes {
  int up = -1, along = 0, across = 0;
  float extent[3] = {0, 0, 0};
};

Axes axes_of(const ModelData& model) {
  Axes a;
  for (int k = 0; k < 3; ++k) a.extent[k] = model.bbox_max[k] - model.bbox_min[k];
  const int thinnest = int(std::min_element(a.extent, a.extent + 3) - a.extent);
  a.along = thinnest == 0 ? 1 : 0;
  a.across = 3 - thinnest - a.along;
  if (a.extent[thinnest] * 4 <= std::min(a.extent[a.along], a.extent[a.across])) a.up = thinnest;
  return a;
}

Camera land_camera(const Axes& a) {
  Camera c;
  c.width = 800;
  c.height = 450;
  c.fovy_deg = 50;
  c.up[0] = c.up[1] = c.up[2] = 0;
  c.up[a.up] = 1;
  return c;
}

Camera first_orbit_camera(const ModelData& model) {
  PathOptions options;
  options.frames = 1;
  return make_camera_path(PathKind::orbit, model, options).front();
}

}  // namespace

std::vector<Camera> demo_flight_path(const ModelData& model, uint32_t frames) {
  const Axes a = axes_of(model);
  if (a.up < 0) {
    PathOptions options;
    options.frames = frames;
    return make_camera_path(PathKind::orbit, model, options);
  }
  std::vector<Camera> path;
  const float altitude = model.bbox_max[a.up] + 0.08f * a.extent[a.along];
  for (uint32_t i = 0; i < frames; ++i) {
    const float t = float(i) / float(std::max(1u, frames - 1));
    Camera c = land_camera(a);
    // Across the terrain with a gentle weave, looking ahead and down at the ground in front.
    const float s = 0.05f + 0.7f * t;
    c.eye[a.along] = model.bbox_min[a.along] + s * a.extent[a.along];
    c.eye[a.across] = model.bbox_min[a.across] + (0.5f + 0.15f * std::sin(6.0f * t)) * a.extent[a.across];
    c.eye[a.up] = altitude;
    std::copy_n(c.eye, 3, c.target);
    c.target[a.along] += 0.15f * a.extent[a.along];
    c.target[a.up] = model.bbox_min[a.up] + 0.5f * a.extent[a.up];
    path.push_back(c);
  }
  return path;
}

Camera demo_first_view(const ModelData& model) {
  const Axes a = axes_of(model);
  if (a.up < 0) return first_orbit_camera(model);
  Camera c = land_camera(a);
  c.eye[a.along] = model.bbox_min[a.along] - 0.1f * a.extent[a.along];
  c.eye[a.across] = model.bbox_min[a.across] + 0.5f * a.extent[a.across];
  c.eye[a.up] = model.bbox_max[a.up] + 0.11f * a.extent[a.along];
  std::copy_n(c.eye, 3, c.target);
  c.target[a.along] = model.bbox_min[a.along] + 0.4f * a.extent[a.along];
  c.target[a.up] = model.bbox_min[a.up] + 0.25f * a.extent[a.up];
  return c;
}

RenderOptions demo_snapshot_look(const ModelData& model) {
  RenderOptions look;
  const Axes a = axes_of(model);
  if (a.up < 0) return look;
  look.light[a.along] = 0.6f;
  look.light[a.across] = 0.45f;
  look.light[a.up] = -1;
  look.ambient = 0.3f;
  const uint8_t sky[3] = {150, 190, 230};
  std::copy_n(sky, 3, look.background);
  return look;
}

}  // namespace pms::app
