// pmstream render (MESH|FILE.pms) --camera CAM.json -o OUT.png [--width W --height H]
#include <cstdio>
#include <limits>

#include "apps/commands.h"
#include "apps/render_input.h"
#include "apps/resource_usage.h"
#include "render/render.h"

namespace pms::app {
namespace {

struct RenderArgs {
  std::string input, output;
  CameraArgs view;
};

void run_render(const RenderArgs& args) {
  Stopwatch clock;
  // The camera first: a typo in it should not cost loading a big model.
  const Camera camera = load_camera_sized(args.view);
  const Mesh mesh = load_render_input(args.input);
  float lo[3], hi[3];
  std::fill(lo, lo + 3, std::numeric_limits<float>::infinity());
  std::fill(hi, hi + 3, -std::numeric_limits<float>::infinity());
  extend_bounds(mesh, lo, hi);
  const ViewParams view = render_view(camera, args.view.camera, lo, hi);
  const Image image = render(render_mesh(mesh), view);
  save_png(args.output, image);
  std::printf("%s: %zu faces, %zu visible, %ux%u -> %s (%.2f s)\n", args.input.c_str(), mesh.face_count(),
              visible_faces(image).size(), image.width, image.height, args.output.c_str(), clock.seconds());
}

}  // namespace

void add_render_command(CliCommand& app) {
  auto args = std::make_shared<RenderArgs>();
  CliCommand cmd = app.subcommand("render", "Render a mesh or a .pms model (its finest mesh) to PNG");
  cmd.option("input", args->input, "Mesh file, terrain:FACES, or .pms model").required();
  add_camera_options(cmd, args->view);
  cmd.option("-o,--output", args->output, "Output .png file").required().writes({".png"}, "PNG");
  cmd.on_run([args] { run_render(*args); });
}

}  // namespace pms::app
