// pmstream demo: the main job on the built-in model — a procedural terrain (the flight-simulator
// scene of kim-lee-kobbelt §3) built into a view-dependent progressive mesh, then refined.
// Later stages (streaming server + headless client) grow from here; this stays the single entry point.
#include <cstdio>
#include <filesystem>

#include "apps/build_pipeline.h"
#include "apps/commands.h"
#include "apps/demo_flight.h"
#include "apps/progress_bar.h"
#include "apps/refine_pipeline.h"
#include "apps/resource_usage.h"
#include "common/error.h"

namespace pms::app {
namespace {

constexpr uint64_t kDemoFaces = 600'000;
constexpr double kRefinedShare = 0.1;  // the partly refined mesh applies this share of the splits

struct DemoArgs {
  std::string out_dir = "demo-out";
  bool rebuild = false;
  uint32_t frames = 240;
  float tolerance = 1;
};

// The cached build is reused only if it was made from the same generator input by this version.
bool cache_is_current(const std::string& path, const std::string& input_name) {
  if (!std::filesystem::exists(path)) return false;
  try {
    const auto file = PmsFile::open(path);
    return file->stats().input_name == input_name && file->stats().tool_version == PMSTREAM_VERSION;
  } catch (const Error&) {
    return false;  // corrupt or older format: build again
  }
}

void run_demo(const DemoArgs& args) {
  std::filesystem::create_directories(args.out_dir);
  const std::string input_name = "terrain:" + std::to_string(kDemoFaces);
  const std::string pms_path = args.out_dir + "/terrain.pms";
  if (args.rebuild || !cache_is_current(pms_path, input_name)) {
    std::printf("building the built-in terrain (%llu faces) into %s\n", (unsigned long long)kDemoFaces, pms_path.c_str());
    Stopwatch clock;
    ProgressBar bar(true);
    BuildOptions options;
    options.progress = bar.callback();
    const BuildRun run = build_file(input_name, pms_path, options);
    bar.finish();
    std::printf("  built in %.2f s (generate %.2f, clean %.2f, build+write %.2f), peak RSS %.0f MB\n", clock.seconds(),
                run.load_seconds, run.clean_seconds, run.build_seconds, peak_rss_mb());
  } else {
    std::printf("using the cached build %s (--rebuild to build again)\n", pms_path.c_str());
  }
  const auto file = PmsFile::open(pms_path);
  const ModelView& model = file->view();
  const BuildStats& s = file->stats();
  std::printf("model:     %llu vertices, %llu faces; base %u vertices, %zu faces; %zu vsplits\n",
              (unsigned long long)s.input_vertices, (unsigned long long)s.input_faces, model.root_count,
              model.base_faces.size() / 3, model.split_order.size());
  std::printf("ids:       <%u, %u> bits (tree, node); file %llu bytes\n", s.tree_id_bits, s.node_id_bits,
              (unsigned long long)file->file_size());

  const std::string coarse = args.out_dir + "/coarse.ply", refined = args.out_dir + "/refined.ply";
  const Mesh base = refine_first_splits(model, 0);
  save_ply(base, coarse);
  const uint64_t k = uint64_t(double(model.split_order.size()) * kRefinedShare);
  Stopwatch clock;
  const Mesh partial = refine_first_splits(model, k);
  const double seconds = clock.seconds();
  save_ply(partial, refined);
  std::printf("wrote:     %s (%zu faces), %s (%llu splits in %.3f s -> %zu faces)\n", coarse.c_str(), base.face_count(),
              refined.c_str(), (unsigned long long)k, seconds, partial.face_count());

  FlightOptions flight;
  flight.out_dir = args.out_dir;
  flight.frames = args.frames;
  flight.tolerance = args.tolerance;
  run_demo_flight(pms_path, "terrain", flight);
}

}  // namespace

void add_demo_command(CLI::App& app) {
  auto args = std::make_shared<DemoArgs>();
  CLI::App* cmd = app.add_subcommand("demo", "Build the built-in terrain and stream it to a headless client over loopback (no input needed)");
  cmd->add_option("--out", args->out_dir, "Output directory")->capture_default_str();
  cmd->add_flag("--rebuild", args->rebuild, "Ignore the cached build");
  cmd->add_option("--frames", args->frames, "Frames of the flight")->check(CLI::Range(1u, 100000u))->capture_default_str();
  cmd->add_option("--tolerance", args->tolerance, "Screen-space error tolerance in pixels")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->callback([args] { run_demo(*args); });
}

}  // namespace pms::app
