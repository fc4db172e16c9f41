// pmstream demo: the main job on the built-in model — a procedural terrain with land colours (the
// flight-simulator scene of kim-lee-kobbelt §3) — or on the user's own (--model): built into a
// view-dependent progressive mesh (cached), then either served to the browser page on loopback until Ctrl-C
// (on a terminal, or --serve: apps/demo_serve.h) or refined and streamed to a headless client over loopback
// (--headless, or without a terminal: apps/demo_flight.h).
#include <unistd.h>
#include <cstdio>
#include <filesystem>

#include "apps/build_pipeline.h"
#include "apps/commands.h"
#include "apps/demo_flight.h"
#include "apps/demo_serve.h"
#include "apps/demo_views.h"
#include "apps/progress_bar.h"
#include "apps/refine_pipeline.h"
#include "apps/resource_usage.h"
#include "common/error.h"
#include "spm/hierarchy.h"
#include "spm/pms_file.h"

namespace pms::app {
namespace {

constexpr uint64_t kDemoFaces = 600'000;
constexpr double kRefinedShare = 0.1;  // the partly refined mesh applies this share of the splits

namespace fs = std::filesystem;

struct DemoArgs {
  std::string model;  // empty: the built-in terrain
  std::string out_dir = "demo-out";
  bool rebuild = false;
  uint32_t frames = 240;
  float tolerance = 1;
  bool headless = false;  // the finite flight, even on a terminal
  bool serve = false;     // the page, even without a terminal
  DemoServeOptions page;
};

// The cached build is reused only if it was made from the same input with the same options by this
// version, and (for a file) after the input last changed.
bool cache_is_current(const std::string& path, const std::string& input_name, const std::string& input_file) {
  if (!fs::exists(path)) return false;
  try {
    if (!input_file.empty() && fs::last_write_time(path) < fs::last_write_time(input_file)) return false;
    const auto file = PmsFile::open(path);
    const BuildStats& stats = file->stats();
    return stats.input_name == input_name && stats.tool_version == PMSTREAM_VERSION &&
           stats.options == options_text(BuildOptions{});
  } catch (const Error&) {
    return false;  // corrupt or older format: build again
  }
}

// "bunny" for bunny.ply.xz: the name the server gives the built file.
std::string model_name_of(const fs::path& file) {
  fs::path name = file.filename();
  if (name.extension() == ".gz" || name.extension() == ".xz") name = name.stem();
  return name.stem().string();
}

// The .pms to stream: the user's own file as it is, or a build of their mesh or of the built-in terrain,
// cached in the output directory.
std::string prepare_model(const DemoArgs& args) {
  if (!args.model.empty() && fs::path(args.model).extension() == ".pms") return args.model;
  if (!args.model.empty() && !fs::is_regular_file(args.model)) fail(args.model, "no such file");
  const bool own = !args.model.empty();
  // What the build records as its input: a file's name (its date decides, as for make), or the generator.
  const std::string input_name =
      own ? fs::path(args.model).filename().string() : "terrain:" + std::to_string(kDemoFaces) + ":colors";
  const std::string pms_path = args.out_dir + "/" + (own ? model_name_of(args.model) : "terrain") + ".pms";
  if (args.rebuild || !cache_is_current(pms_path, input_name, own ? args.model : "")) {
    if (own) std::printf("building %s into %s\n", args.model.c_str(), pms_path.c_str());
    else
      std::printf("building the built-in terrain (%llu faces, coloured) into %s\n", (unsigned long long)kDemoFaces,
                  pms_path.c_str());
    Stopwatch clock;
    ProgressBar bar(true);
    BuildOptions options;
    options.progress = bar.callback();
    // The server and client of the flight run in this process next: the build tunes malloc only as far as
    // it can undo (apps/build_memory.h).
    const BuildRun run = build_file(own ? args.model : input_name, pms_path, options, AfterBuild::kServe);
    bar.finish();
    std::printf("  built in %.2f s (load %.2f, clean %.2f, hierarchy %.2f, write %.2f), peak RSS %.0f MB\n",
                clock.seconds(), run.load_seconds, run.clean_seconds, run.build_seconds - run.write_seconds,
                run.write_seconds, peak_rss_mb());
  } else {
    std::printf("using the cached build %s (--rebuild to build again)\n", pms_path.c_str());
  }
  return pms_path;
}

void print_model(const PmsFile& file) {
  const ModelData& model = file.model();
  const BuildStats& s = file.stats();
  std::printf("model:     %llu vertices, %llu faces; base %u vertices, %zu faces; %zu vsplits\n",
              (unsigned long long)s.input_vertices, (unsigned long long)s.input_faces, model.root_count,
              model.base_faces.size() / 3, model.split_order.size());
  std::printf("ids:       <%u, %u> bits (tree, node); file %llu bytes\n", s.tree_id_bits, s.node_id_bits,
              (unsigned long long)file.file_size());
}

// The headless run's meshes beside its report: the base mesh and one with a share of the splits applied.
void write_meshes(const ModelData& model, const std::string& out_dir) {
  const std::string coarse = out_dir + "/coarse.ply", refined = out_dir + "/refined.ply";
  const Mesh base = refine_first_splits(model, 0);
  save_ply(base, coarse);
  const uint64_t k = uint64_t(double(model.split_order.size()) * kRefinedShare);
  Stopwatch clock;
  const Mesh partial = refine_first_splits(model, k);
  const double seconds = clock.seconds();
  save_ply(partial, refined);
  std::printf("wrote:     %s (%zu faces), %s (%llu splits in %.3f s -> %zu faces)\n", coarse.c_str(), base.face_count(),
              refined.c_str(), (unsigned long long)k, seconds, partial.face_count());
}

void run_demo(const DemoArgs& args, bool serve) {
  if (args.rebuild && fs::path(args.model).extension() == ".pms")
    fail("--rebuild", "not used with a .pms --model (it is streamed as it is, nothing is built)");
  fs::create_directories(args.out_dir);
  const std::string pms_path = prepare_model(args);
  const auto file = PmsFile::open(pms_path);
  print_model(*file);
  const std::string name = model_name_of(pms_path);
  if (serve) {
    DemoServeOptions page = args.page;
    page.tolerance = args.tolerance;
    serve_demo(pms_path, name, demo_first_view(file->model()), page);
    return;
  }
  write_meshes(file->model(), args.out_dir);
  FlightOptions flight;
  flight.out_dir = args.out_dir;
  flight.frames = args.frames;
  flight.tolerance = args.tolerance;
  run_demo_flight(pms_path, name, flight);
}

}  // namespace

void add_demo_command(CliCommand& app) {
  auto args = std::make_shared<DemoArgs>();
  CliCommand cmd = app.subcommand(
      "demo",
      "Build the built-in terrain and serve it to the browser page on loopback (on a terminal), or stream it to a "
      "headless client (--headless, or without a terminal); no input needed");
  cmd.option("--model", args->model,
             "Your own model instead of the terrain: a .pms file, or a mesh file (PLY, OBJ, OFF, STL, glTF/GLB; may "
             "end in .gz or .xz) built into the output directory first (cached)");
  cmd.option("--out", args->out_dir, "Output directory").show_default();
  cmd.flag("--rebuild", args->rebuild, "Ignore the cached build");
  cmd.option("--tolerance", args->tolerance, "Screen-space error tolerance in pixels").non_negative().show_default();
  const CliOption headless =
      cmd.flag("--headless", args->headless,
               "Fly the headless client and write the report, even on a terminal (the default without one)");
  CliOption serve =
      cmd.flag("--serve", args->serve, "Serve the page until Ctrl-C, even without a terminal (the default on one)");
  serve.excludes(headless);
  // Each half's own options, refused in the other (cli.h, VariantOption).
  const std::vector<VariantOption> by_half = {
      {cmd.option("--frames", args->frames, "Frames of the flight").range(1u, 100000u).show_default(), {"--headless"}},
      {cmd.option("--port", args->page.port,
                  "TCP port for native clients (0: any free port; the default, if taken, falls back to one)")
           .show_default(),
       {"--serve"}},
      {cmd.option("--http-port", args->page.http_port,
                  "HTTP port of the page, its WebSocket and the HTTP modes (0: any free port; the default, if taken, "
                  "falls back "
                  "to one)")
           .show_default(),
       {"--serve"}},
      {cmd.option("--web-root", args->page.web_root,
                  "Directory of the page (default: web/ beside the pmstream executable)"),
       {"--serve"}}};
  cmd.on_run([args, by_half] {
    const bool terminal = isatty(fileno(stdout));
    const bool serve = args->serve || (terminal && !args->headless);
    const std::string chosen = args->serve      ? "--serve"
                               : args->headless ? "--headless"
                               : terminal       ? "a run on a terminal, which serves the page"
                                                : "a run without a terminal, which flies the headless client";
    refuse_unused_options(by_half, serve ? "--serve" : "--headless", chosen);
    // The default ports are a convenience: taken by another program, any free ones do (the link says which).
    args->page.any_port_if_taken = !by_half[1].option.given() && !by_half[2].option.given();
    run_demo(*args, serve);
  });
}

}  // namespace pms::app
