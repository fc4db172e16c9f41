// pmstream path (orbit|scan|zoom|look|rotate) --model FILE.pms --frames N -o PATH.json [--width W --height H --fovy F]
#include <cstdio>

#include "apps/camera_json.h"
#include "apps/camera_path.h"
#include "apps/commands.h"
#include "common/error.h"
#include "spm/pms_file.h"

namespace pms::app {
namespace {

struct PathArgs {
  std::string kind, model, output;
  PathOptions options;
};

void run_path(const PathArgs& args) {
  const PathKind kind = parse_path_kind(args.kind);
  const auto file = PmsFile::open(args.model);
  const std::vector<Camera> frames = make_camera_path(kind, file->model(), args.options);
  save_path(args.output, frames);
  std::printf("%s path over %s: %zu frames -> %s\n", args.kind.c_str(), args.model.c_str(), frames.size(),
              args.output.c_str());
}

}  // namespace

void add_path_command(CliCommand& app) {
  auto args = std::make_shared<PathArgs>();
  CliCommand cmd = app.subcommand("path", "Write a scripted camera path (PATH.json) around a .pms model");
  cmd.option("kind", args->kind,
             "orbit (circle around the model), scan (close, bottom to top), zoom (far to close-up), look (around "
             "the model from top to bottom) or rotate (in close while circling faster and faster)")
      .required()
      .one_of({"orbit", "scan", "zoom", "look", "rotate"});
  cmd.option("--model", args->model, ".pms file the path is made for").required();
  cmd.option("--frames", args->options.frames, "Number of cameras").required().range(1, 1000000);
  cmd.option("-o,--output", args->output, "Output PATH.json").required().writes({".json"}, "JSON");
  cmd.option("--width", args->options.width, "Viewport width in pixels (default 800)").range(1, 16384);
  cmd.option("--height", args->options.height, "Viewport height in pixels (default 600)").range(1, 16384);
  cmd.option("--fovy", args->options.fovy_deg, "Vertical field of view in degrees (default 45)");
  cmd.on_run([args] { run_path(*args); });
}

}  // namespace pms::app
