// What `render` and `compare` draw, and the view they draw it with.
#pragma once
#include <cstdint>
#include <string>

#include "apps/cli.h"
#include "common/camera.h"
#include "io/mesh.h"
#include "render/render.h"

namespace pms::app {

// A .pms model renders its finest mesh (every vsplit applied, = the cleaned input); anything else is read
// as build's input is (a mesh file in any supported format, or "terrain:FACES"), uncleaned: the image
// shows the file as it is. Throws pms::Error naming the file.
Mesh load_render_input(const std::string& path);

inline RenderMesh render_mesh(const Mesh& mesh) { return {mesh.positions, mesh.indices, mesh.colors}; }

// Grows [box_min, box_max] (start from +inf / -inf) by the mesh's vertices.
void extend_bounds(const Mesh& mesh, float box_min[3], float box_max[3]);

// The camera of CAM.json with --width / --height applied (0 = keep the file's).
Camera load_camera_sized(const std::string& path, uint32_t width, uint32_t height);

// --camera CAM.json (required), --width and --height, as `render` and `compare` take them.
struct CameraArgs {
  std::string camera;
  uint32_t width = 0, height = 0;  // 0: the camera file's
};
void add_camera_options(CliCommand& cmd, CameraArgs& args);
inline Camera load_camera_sized(const CameraArgs& args) {
  return load_camera_sized(args.camera, args.width, args.height);
}

// make_view() with near/far around [box_min, box_max] (an empty box, min > max, becomes the camera's
// target point); a degenerate camera is reported against `camera_path`.
ViewParams render_view(const Camera& camera, const std::string& camera_path, const float box_min[3],
                       const float box_max[3]);

}  // namespace pms::app
