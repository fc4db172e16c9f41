// pmstream compare MESH_A MESH_B --camera CAM.json [--json]
// Both meshes are drawn with one ViewParams (near/far around the union of their boxes), so the images
// differ only where the meshes do. Metrics as cheng-ooi 2008 Table 2 (see render/render.h).
#include <cmath>
#include <cstdio>
#include <limits>

#include <nlohmann/json.hpp>

#include "apps/commands.h"
#include "apps/render_input.h"
#include "render/render.h"

namespace pms::app {
namespace {

struct CompareArgs {
  std::string a, b;
  CameraArgs view;
  bool json = false;
};

void run_compare(const CompareArgs& args) {
  const Camera camera = load_camera_sized(args.view);
  const Mesh mesh_a = load_render_input(args.a);
  const Mesh mesh_b = load_render_input(args.b);
  float lo[3], hi[3];
  std::fill(lo, lo + 3, std::numeric_limits<float>::infinity());
  std::fill(hi, hi + 3, -std::numeric_limits<float>::infinity());
  extend_bounds(mesh_a, lo, hi);
  extend_bounds(mesh_b, lo, hi);
  const ViewParams view = render_view(camera, args.view.camera, lo, hi);
  Renderer renderer;
  Image image_a, image_b;
  renderer.render(render_mesh(mesh_a), view, image_a);
  renderer.render(render_mesh(mesh_b), view, image_b);
  const ImageMetrics m = compare_images(image_a, image_b);
  if (args.json) {
    const nlohmann::json out = {{"psnr", std::isinf(m.psnr) ? kPsnrIdenticalJson : m.psnr},
                                {"error_pixels", m.error_pixels},
                                {"error_fraction", m.error_fraction}};
    std::printf("%s\n", out.dump().c_str());
    return;
  }
  if (std::isinf(m.psnr))
    std::printf("psnr inf dB (identical), error pixels 0 of %ux%u\n", image_a.width, image_a.height);
  else
    std::printf("psnr %.2f dB, error pixels %llu of %ux%u (%.4f%%)\n", m.psnr, (unsigned long long)m.error_pixels,
                image_a.width, image_a.height, 100.0 * m.error_fraction);
}

}  // namespace

void add_compare_command(CliCommand& app) {
  auto args = std::make_shared<CompareArgs>();
  CliCommand cmd = app.subcommand("compare", "Render two meshes with one camera and compare the images");
  cmd.option("mesh_a", args->a, "Mesh file, terrain:FACES, or .pms model").required();
  cmd.option("mesh_b", args->b, "Mesh file, terrain:FACES, or .pms model").required();
  add_camera_options(cmd, args->view);
  cmd.flag("--json", args->json, "Print one JSON object: psnr error_pixels error_fraction");
  cmd.on_run([args] { run_compare(*args); });
}

}  // namespace pms::app
