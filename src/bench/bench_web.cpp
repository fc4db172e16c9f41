// The "web" group (docs/architecture.md, "Experiments"; docs/web.md): the browser viewer in Debian's
// chromium, headless with software WebGL at 1280×720, against a `pmstream serve` of dragon with the built
// site. The browser side is bench/web/web_bench.mjs (node + playwright-core), which prints what it measured
// as JSON; this file starts the server, runs the same refinement natively for the WASM-vs-native ratio and
// turns both into the figures and their targets. The browser missing is a skip with a line saying so.
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "apps/camera_json.h"
#include "apps/camera_path.h"
#include "apps/percentile.h"
#include "apps/resource_usage.h"
#include "bench/bench.h"
#include "bench/bench_model.h"
#include "bench/bench_refine.h"
#include "bench/child_process.h"
#include "bench/report.h"
#include "bench/serve_child.h"
#include "bench/web_figures.h"
#include "spm/path_refinement.h"

namespace pms::bench {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr const char* kModel = "dragon";
constexpr float kTolerancePx = 1;
// The refinement run: the orbit flown kRefineLaps times per run (one lap is too short for a shared machine's
// clock), kRefineRepeats runs a side after one untimed (the browser compiles WASM in tiers: the first run
// is partly the baseline compiler's), the fastest of them the figure (the least disturbed).
constexpr uint32_t kRefineLaps = 5;
constexpr uint32_t kRefineRepeats = 5;

// What a full run and a --quick one do.
struct WebPlan {
  uint32_t path_frames, loads, laps;
  double lap_seconds, settle_seconds;
};
constexpr WebPlan kFull = {180, 5, 5, 60, 180};
constexpr WebPlan kQuick = {60, 2, 5, 8, 60};

std::string chromium_path() {
  const char* env = std::getenv("PMSTREAM_CHROMIUM");
  return env && *env ? env : "/usr/bin/chromium";
}

// Why the group cannot run here, or empty.
std::string missing_browser_parts(const std::string& node, const fs::path& site) {
  if (!fs::exists(chromium_path())) return "chromium is not installed at " + chromium_path();
  if (node.empty()) return "node is not on PATH";
  if (!fs::exists(PMSTREAM_WEB_BENCH_DRIVER)) return std::string(PMSTREAM_WEB_BENCH_DRIVER) + " is missing";
  for (const char* file : {"index.html", "pmstream_core.wasm", "vendor/three.module.js"})
    if (!fs::exists(site / file))
      return "the site is not built (" + (site / file).string() + " missing; PMSTREAM_WEB=ON)";
  return "";
}

// The built site and the model's .pms beside it (the page fetches that for the WASM refinement run), in
// the run's scratch space: the server serves only files under its root.
fs::path site_with_model(const BenchContext& context, const fs::path& site, const BenchModel& m) {
  const fs::path root = context.temp_dir / "site";
  fs::remove_all(root);
  fs::copy(site, root, fs::copy_options::recursive);
  fs::create_directories(root / "bench");
  fs::copy_file(m.pms, root / "bench" / (m.name + ".pms"));
  return root;
}

// The native side of the WASM-vs-native ratio: the same function over the same model and cameras,
// appended to `runs`.
void native_refinement(const BenchModel& m, const std::vector<Camera>& path, json& runs) {
  std::vector<Camera> laps;
  for (uint32_t lap = 0; lap < kRefineLaps; ++lap) laps.insert(laps.end(), path.begin(), path.end());
  refine_along(m.served->model(), laps, kTolerancePx);
  for (uint32_t i = 0; i < kRefineRepeats; ++i) {
    const PathRefinement run = refine_along(m.served->model(), laps, kTolerancePx);
    runs.push_back({{"ops", run.ops}, {"seconds", run.seconds}, {"faces", run.faces}, {"frames", run.frames}});
  }
}

// The 1-minute load average: the browser's figures are the machine's share it got, so the report says it.
std::string load_average() {
  std::ifstream in("/proc/loadavg");
  std::string one;
  in >> one;
  return one.empty() ? "?" : one;
}

}  // namespace

void run_web_group(BenchContext& context) {
  std::string section = "## web: the browser viewer in headless Chromium\n\n";
  if (skipped_without_models(context, section)) return;
  const std::string node = find_program("node");
  const fs::path site = fs::path(context.pmstream_exe).parent_path() / "web";
  if (const std::string missing = missing_browser_parts(node, site); !missing.empty()) {
    section += "Skipped: " + missing + ".\n\n";
    print_now("\n" + section);
    context.report += section;
    return;
  }
  const app::Stopwatch clock;
  const WebPlan plan = context.options.quick ? kQuick : kFull;
  const BenchModel m = prepare_model(context, kModel);
  const fs::path root = site_with_model(context, site, m);
  ServeChild server(context.pmstream_exe,
                    {m.pms.string(), "--http-port", "0", "--web-root", root.string(), "--preload", "all"});
  const std::string url = "http://127.0.0.1:" + std::to_string(server.listening()["http_port"].get<uint16_t>());

  app::PathOptions options;
  options.frames = plan.path_frames;
  options.fovy_deg = 60;
  options.width = 1280;
  options.height = 720;
  const std::vector<Camera> path = app::make_camera_path(app::PathKind::orbit, m.served->model(), options);
  const fs::path path_file = context.temp_dir / "web-orbit.json";
  app::save_path(path_file.string(), path);
  const json config = {{"url", url},
                       {"model", m.name},
                       {"pmsUrl", "/bench/" + m.name + ".pms"},
                       {"pathFile", path_file.string()},
                       {"modes", {"sender", "sender-plain", "vi", "dag", "receiver", "multilevel"}},
                       {"tolerance", kTolerancePx},
                       {"loads", plan.loads},
                       {"refineRepeats", kRefineRepeats},
                       {"refineLaps", kRefineLaps},
                       {"laps", plan.laps},
                       {"lapSeconds", plan.lap_seconds},
                       {"settleSeconds", plan.settle_seconds}};
  const fs::path config_file = context.temp_dir / "web-bench.json";
  write_text_file(config_file, config.dump(2));

  std::fprintf(stderr, "bench: web, native refinement along the orbit\n");
  const std::string load_before = load_average();
  json native = json::array();
  native_refinement(m, path, native);
  std::fprintf(stderr, "bench: web, the browser (%s)\n", PMSTREAM_WEB_BENCH_DRIVER);
  ChildOptions child;
  child.timeout_seconds = 1800 + plan.laps * plan.lap_seconds;
  const ChildResult result = run_child({node, PMSTREAM_WEB_BENCH_DRIVER, config_file.string()}, child);
  server.stop();
  native_refinement(m, path, native);
  const std::string load_after = load_average();
  if (!result.ok()) {
    context.failures.push_back("web: the browser driver: " + result.failure());
    section += "The browser driver failed: " + result.failure() + "\n\n";
    print_now("\n" + section);
    context.report += section;
    return;
  }
  const json browser = json::parse(result.out);
  if (browser.contains("skipped")) {
    section += "Skipped: " + browser["skipped"].get<std::string>() + ".\n\n";
    print_now("\n" + section);
    context.report += section;
    return;
  }
  const WebFigures figures = web_figures(browser, native);
  section += "Model " + m.name + " at τ = " + fixed(kTolerancePx, 0) + " px, " + browser.value("browser", "") +
             " headless with SwiftShader's WebGL at 1280×720, the server on loopback with every table preloaded. "
             "The path is `pmstream path orbit` (" +
             std::to_string(plan.path_frames) +
             " cameras, 60° field of view), one camera per displayed frame. The group took " +
             fixed(clock.seconds() / 60, 1) + " minutes; the 1-minute load average was " + load_before +
             " before the browser's run and " + load_after +
             " after it (2 cores here: frame rates and CPU times are what the page got of a shared machine).\n\n";
  section += web_report(figures, plan.lap_seconds);
  print_now("\n" + section);
  write_text_file(context.options.out_dir / "web.json", json{{"model", m.name},
                                                             {"figures", figures_json(figures)},
                                                             {"browser", browser.value("browser", "")},
                                                             {"wasm_refinement", browser["refine"]},
                                                             {"native_refinement", native},
                                                             {"first_pictures", browser["firstPicture"]}}
                                                                .dump(2) +
                                                            "\n");
  context.report += section;
}

}  // namespace pms::bench
