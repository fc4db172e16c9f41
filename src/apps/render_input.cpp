#include "apps/render_input.h"

#include <algorithm>
#include <cctype>
#include <limits>

#include "apps/build_pipeline.h"
#include "apps/camera_json.h"
#include "apps/refine_pipeline.h"
#include "common/error.h"
#include "spm/pms_file.h"

namespace pms::app {
namespace {

bool is_pms(const std::string& path) {
  if (path.size() < 4) return false;
  std::string ext = path.substr(path.size() - 4);
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return ext == ".pms";
}

}  // namespace

Mesh load_render_input(const std::string& path) {
  if (!is_pms(path)) return load_input(path, {});
  const auto file = PmsFile::open(path);
  try {
    return refine_first_splits(file->model(), std::numeric_limits<uint64_t>::max());
  } catch (const Error& e) {
    fail(path, e.what());  // the refinement's own errors do not know the file
  }
}

void extend_bounds(const Mesh& mesh, float box_min[3], float box_max[3]) {
  for (size_t v = 0; v < mesh.vertex_count(); ++v)
    for (int k = 0; k < 3; ++k) {
      box_min[k] = std::min(box_min[k], mesh.positions[3 * v + k]);
      box_max[k] = std::max(box_max[k], mesh.positions[3 * v + k]);
    }
}

Camera load_camera_sized(const std::string& path, uint32_t width, uint32_t height) {
  Camera camera = load_camera(path);
  if (width) camera.width = width;
  if (height) camera.height = height;
  return camera;
}

ViewParams render_view(const Camera& camera, const std::string& camera_path, const float box_min[3],
                       const float box_max[3]) {
  float lo[3], hi[3];
  const bool empty = !(box_min[0] <= box_max[0] && box_min[1] <= box_max[1] && box_min[2] <= box_max[2]);
  for (int k = 0; k < 3; ++k) {
    lo[k] = empty ? camera.target[k] : box_min[k];
    hi[k] = empty ? camera.target[k] : box_max[k];
  }
  try {
    return make_view(camera, lo, hi);
  } catch (const Error& e) {
    fail(camera_path, e.what());
  }
}

void add_camera_options(CliCommand& cmd, CameraArgs& args) {
  cmd.option("--camera", args.camera, "Camera JSON (CAM.json, docs/cli.md)").required();
  cmd.option("--width", args.width, "Image width (overrides the camera's)").range(1, 16384);
  cmd.option("--height", args.height, "Image height (overrides the camera's)").range(1, 16384);
}

}  // namespace pms::app
