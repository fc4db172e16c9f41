// The web group's figures (bench_web.cpp) out of what the browser driver measured (bench/web/web_bench.mjs)
// and the native refinement run, each beside its target (issue's "Targets (bench)"), and their report.
#pragma once
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace pms::bench {

struct ModeFlight {
  std::string mode;
  uint32_t frames = 0;
  double fps = 0;
  // The page's CPU per frame: its main thread's CPU time in each animation-frame callback (tracing), which
  // is all of its frame work (the viewer's frame, buffer updates, render call, overlay) and, unlike the
  // clock, not the time the thread waited for a core on a shared machine.
  double cpu_p50_ms = 0, cpu_p99_ms = 0;
  uint32_t cpu_frames = 0;                  // callbacks traced; 0: the trace had none, the CPU is not measured
  double step_p50_ms = 0, step_p99_ms = 0;  // the frame work (viewer frame + buffer updates + JS) by the clock
  double core_p50_ms = 0, core_p99_ms = 0;  // the viewer's frame() alone (WASM and the binding), by the clock
  double render_p50_ms = 0;                 // three.js's render() call, by the clock
  uint64_t faces = 0, down_bytes = 0;
  bool settled_before = false;
};

struct LapMemory {
  uint32_t frames = 0;
  uint64_t heap_bytes = 0, wasm_bytes = 0;
};

// A CPU profile's self time: by category (WASM core, three.js, ...) and by function.
struct ProfileShare {
  std::string name;
  double ms = 0;
};

struct WebFigures {
  double native_ops_per_s = 0, wasm_ops_per_s = 0;
  std::vector<double> first_picture_ms;
  double first_picture_median_ms = 0;
  uint64_t model_bytes = 0, site_bytes = 0;  // until the first picture, on the median load
  // On the median load: the page's last file in, the core instantiated, the viewer opened (ms).
  double site_ms = 0, core_ms = 0, viewer_ms = 0;
  double streamed_fps = 0, replayed_fps = 0;
  uint32_t replay_frames = 0;
  std::vector<ModeFlight> modes;
  std::vector<LapMemory> laps;
  std::vector<std::string> page_errors;  // console and page errors the driver saw
  // The sender flight under the profiler: its samples' total, the flight's span, the page's own CPU time.
  double profile_ms = 0, profile_flight_ms = 0, profile_step_ms = 0;
  std::vector<ProfileShare> profile_categories, profile_functions;

  double refine_ratio() const { return native_ops_per_s > 0 ? wasm_ops_per_s / native_ops_per_s : 0; }
  double fps_ratio() const { return replayed_fps > 0 ? streamed_fps / replayed_fps : 0; }
  // From the second lap to the last; 0 with fewer than three laps.
  double heap_growth() const;
  double wasm_growth() const;
};

// `browser`: the driver's JSON; `native`: [{ops, seconds}] of the native refinement run.
WebFigures web_figures(const nlohmann::json& browser, const nlohmann::json& native);

// The report's tables: the figures against their targets, the modes' flights, the laps.
std::string web_report(const WebFigures& figures, double lap_seconds);
nlohmann::json figures_json(const WebFigures& figures);

}  // namespace pms::bench
