// pmstream refine FILE.pms (--full | --splits K | --camera CAM.json [--tolerance PX]) -o OUT.ply [--json]
#include <cstdio>
#include <limits>

#include "apps/camera_json.h"
#include "apps/commands.h"
#include "apps/refine_pipeline.h"
#include "apps/resource_usage.h"
#include "common/error.h"
#include "spm/hierarchy.h"
#include "spm/pms_file.h"

namespace pms::app {
namespace {

struct RefineArgs {
  std::string input, output, camera;
  bool full = false, json = false;
  uint64_t splits = 0;
  float tolerance = 1;
};

void run_refine(const RefineArgs& args, bool splits_given, bool tolerance_given) {
  const bool camera_given = !args.camera.empty();
  if (int(args.full) + int(splits_given) + int(camera_given) != 1)
    fail("", "give exactly one of --full, --splits K and --camera CAM.json");
  if (tolerance_given && !camera_given) fail("--tolerance", "not used without --camera (it is the view's tolerance)");
  Stopwatch clock;
  const Camera camera = camera_given ? load_camera(args.camera) : Camera{};
  const auto file = PmsFile::open(args.input);
  const ModelData& model = file->model();
  uint64_t applied = 0;
  Mesh mesh;
  if (camera_given) {
    try {  // a camera that parses but cannot see (eye == target, up along the view): name the file
      make_view(camera, model.bbox_min, model.bbox_max);
    } catch (const Error& e) {
      fail(args.camera, e.what());
    }
    mesh = refine_for_camera(model, camera, args.tolerance, &applied);
  } else {
    const uint64_t k = args.full ? std::numeric_limits<uint64_t>::max() : args.splits;
    mesh = refine_first_splits(model, k);
    applied = std::min<uint64_t>(k, model.split_order.size());
  }
  save_ply(mesh, args.output);
  const double seconds = clock.seconds();
  if (args.json) {
    std::printf("{\"vertices\":%zu,\"faces\":%zu,\"vsplits_applied\":%llu,\"seconds\":%.6f}\n", mesh.vertex_count(),
                mesh.face_count(), (unsigned long long)applied, seconds);
  } else {
    std::printf("%s: %llu vsplits applied -> %zu vertices, %zu faces -> %s (%.2f s)\n", args.input.c_str(),
                (unsigned long long)applied, mesh.vertex_count(), mesh.face_count(), args.output.c_str(), seconds);
  }
}

}  // namespace

void add_refine_command(CliCommand& app) {
  auto args = std::make_shared<RefineArgs>();
  CliCommand cmd = app.subcommand("refine", "Refine a .pms model and write the mesh as PLY");
  cmd.option("file", args->input, ".pms file").required();
  cmd.flag("--full", args->full, "Apply every vertex split (the finest mesh = the cleaned input)");
  CliOption splits = cmd.option("--splits", args->splits, "Apply the first K vertex splits in stream order");
  cmd.option("--camera", args->camera,
             "Refine for the view in CAM.json (Hoppe 1997 criteria: frustum, back faces, screen-space error)");
  CliOption tolerance =
      cmd.option("--tolerance", args->tolerance, "Screen-space error tolerance in pixels with --camera (default 1)")
          .non_negative();
  cmd.option("-o,--output", args->output, "Output .ply file").required().writes({".ply"}, "PLY");
  cmd.flag("--json", args->json, "Print one JSON object");
  cmd.on_run([args, splits, tolerance] { run_refine(*args, splits.given(), tolerance.given()); });
}

}  // namespace pms::app
