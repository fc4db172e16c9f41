#include "bench/web_figures.h"

#include <algorithm>

#include "apps/percentile.h"
#include "bench/report.h"

namespace pms::bench {
namespace {

using app::percentile;
using nlohmann::json;

// The targets (docs/architecture.md, "Experiments", web).
constexpr double kMinRefineRatio = 0.6;
constexpr double kMaxFirstPictureMs = 1000;
constexpr double kMinFpsRatio = 0.9;
constexpr double kMaxSenderP99Ms = 4;
constexpr double kMaxGrowth = 0.05;

// `j[key]`, or null when `j` has no such key (the driver's JSON is read, never trusted to be whole).
const json& at(const json& j, const char* key) {
  static const json none;
  if (!j.is_object()) return none;
  const auto it = j.find(key);
  return it != j.end() ? *it : none;
}

// The fastest run's: on a shared machine, the least disturbed one.
double best_ops_per_s(const json& runs) {
  double best = 0;
  if (!runs.is_array()) return 0;
  for (const json& r : runs)
    if (r.value("seconds", 0.0) > 0) best = std::max(best, r.value("ops", 0.0) / r.value("seconds", 0.0));
  return best;
}

// Frames per second over a flight's drawn frames, the first one left out: it may upload a whole mesh.
double frames_per_second(const json& log) {
  if (!log.is_array() || log.size() < 3) return 0;
  const double ms = log.back().value("t", 0.0) - log[1].value("t", 0.0);
  return ms > 0 ? 1000 * double(log.size() - 2) / ms : 0;
}

ModeFlight mode_flight(const std::string& mode, const json& flight) {
  ModeFlight f;
  f.mode = mode;
  std::vector<double> cpu, step, core, render;
  if (const json& traced = at(flight, "frameCpuMs"); traced.is_array())
    for (const json& ms : traced)
      if (ms.is_number()) cpu.push_back(ms.get<double>());
  const json& log = at(flight, "log");
  if (log.is_array())
    for (const json& frame : log) {
      step.push_back(frame.value("stepMs", 0.0));
      core.push_back(frame.value("coreMs", 0.0));
      render.push_back(frame.value("renderMs", 0.0));
    }
  f.frames = uint32_t(step.size());
  f.fps = frames_per_second(log);
  f.cpu_frames = uint32_t(cpu.size());
  f.cpu_p50_ms = percentile(cpu, 0.5);
  f.cpu_p99_ms = percentile(cpu, 0.99);
  f.step_p50_ms = percentile(step, 0.5);
  f.step_p99_ms = percentile(step, 0.99);
  f.core_p50_ms = percentile(core, 0.5);
  f.core_p99_ms = percentile(core, 0.99);
  f.render_p50_ms = percentile(render, 0.5);
  f.faces = flight.value("faces", uint64_t(0));
  f.down_bytes = flight.value("downBytes", uint64_t(0));
  f.settled_before = flight.value("settledBeforeFlight", false);
  return f;
}

double growth(const std::vector<LapMemory>& laps, uint64_t LapMemory::*field) {
  if (laps.size() < 3 || laps[1].*field == 0) return 0;
  return double(laps.back().*field) / double(laps[1].*field) - 1;
}

// The "errors" of `part` (console and page errors the driver saw there), each named by `where`.
void collect_errors(const json& part, const std::string& where, std::vector<std::string>& out) {
  const json& errors = at(part, "errors");
  if (!errors.is_array()) return;
  for (const json& e : errors) out.push_back(where + ": " + (e.is_string() ? e.get<std::string>() : e.dump()));
}

std::vector<ProfileShare> shares(const json& list) {
  std::vector<ProfileShare> out;
  if (list.is_array())
    for (const json& s : list) out.push_back({s.value("name", ""), s.value("ms", 0.0)});
  return out;
}

std::string met(bool ok) { return ok ? "met" : "not met"; }
std::string mb(uint64_t bytes) { return fixed(double(bytes) / (1 << 20), 1) + " MiB"; }

}  // namespace

double WebFigures::heap_growth() const { return growth(laps, &LapMemory::heap_bytes); }
double WebFigures::wasm_growth() const { return growth(laps, &LapMemory::wasm_bytes); }

WebFigures web_figures(const json& browser, const json& native) {
  WebFigures f;
  f.native_ops_per_s = best_ops_per_s(native);
  f.wasm_ops_per_s = best_ops_per_s(at(browser, "refine"));
  std::vector<const json*> loads;
  const json& first_pictures = at(browser, "firstPicture");
  if (first_pictures.is_array())
    for (const json& load : first_pictures) {
      f.first_picture_ms.push_back(load.value("ms", 0.0));
      loads.push_back(&load);
      collect_errors(load, "first picture", f.page_errors);
    }
  std::sort(loads.begin(), loads.end(),
            [](const json* a, const json* b) { return a->value("ms", 0.0) < b->value("ms", 0.0); });
  if (!loads.empty()) {
    const json& median = *loads[(loads.size() - 1) / 2];
    f.first_picture_median_ms = median.value("ms", 0.0);
    f.model_bytes = median.value("downBytes", uint64_t(0)) + median.value("upBytes", uint64_t(0));
    f.site_bytes = median.value("siteBytes", uint64_t(0));
    f.site_ms = median.value("siteMs", 0.0);
    f.core_ms = median.value("coreMs", 0.0);
    f.viewer_ms = median.value("viewerMs", 0.0);
  }
  const json& flights = at(browser, "flights");
  if (flights.is_object())
    for (const auto& [mode, flight] : flights.items()) {
      f.modes.push_back(mode_flight(mode, flight));
      collect_errors(flight, mode, f.page_errors);
    }
  const json& replay = at(browser, "replay");
  f.streamed_fps = frames_per_second(at(replay, "streamed"));
  f.replayed_fps = frames_per_second(at(replay, "replayed"));
  f.replay_frames = replay.is_object() ? replay.value("frames", 0u) : 0;
  collect_errors(replay, "streamed and replayed", f.page_errors);
  const json& memory = at(browser, "memory");
  const json& laps = at(memory, "laps");
  if (laps.is_array())
    for (const json& lap : laps)
      f.laps.push_back(
          {lap.value("frames", 0u), lap.value("heapUsedBytes", uint64_t(0)), lap.value("wasmBytes", uint64_t(0))});
  collect_errors(memory, "laps", f.page_errors);
  const json& profile = at(browser, "profile");
  if (profile.is_object()) {
    f.profile_ms = profile.value("totalMs", 0.0);
    f.profile_flight_ms = profile.value("flightMs", 0.0);
    f.profile_step_ms = profile.value("stepMs", 0.0);
    f.profile_categories = shares(at(profile, "categories"));
    f.profile_functions = shares(at(profile, "functions"));
  }
  return f;
}

namespace {

std::string targets_section(const WebFigures& f) {
  Table targets({{"figure", false}, {"measured", false}, {"target", false}, {"", false}});
  targets.add_row({"WASM refinement / native",
                   fixed(f.refine_ratio(), 2) + " (" + thousands(uint64_t(f.wasm_ops_per_s)) + " / " +
                       thousands(uint64_t(f.native_ops_per_s)) + " ops/s)",
                   "≥ " + fixed(kMinRefineRatio, 1), met(f.refine_ratio() >= kMinRefineRatio)});
  targets.add_row({"first picture after navigation start",
                   fixed(f.first_picture_median_ms, 0) + " ms (median of " + std::to_string(f.first_picture_ms.size()) +
                       " cold loads)",
                   "≤ " + fixed(kMaxFirstPictureMs, 0) + " ms", met(f.first_picture_median_ms <= kMaxFirstPictureMs)});
  targets.add_row(
      {"bytes to first picture", thousands(f.model_bytes) + " model + " + thousands(f.site_bytes) + " site", "", ""});
  targets.add_row(
      {"fps streaming / replaying the same meshes",
       fixed(f.fps_ratio(), 2) + " (" + fixed(f.streamed_fps, 1) + " / " + fixed(f.replayed_fps, 1) + " fps)",
       "≥ " + fixed(kMinFpsRatio, 1), met(f.fps_ratio() >= kMinFpsRatio)});
  const auto sender =
      std::find_if(f.modes.begin(), f.modes.end(), [](const ModeFlight& m) { return m.mode == "sender"; });
  if (sender != f.modes.end()) {
    const bool measured = sender->cpu_frames > 0;
    targets.add_row({"page CPU per frame, sender p99",
                     measured ? fixed(sender->cpu_p99_ms, 2) + " ms (thread time)" : "not measured (no trace)",
                     "≤ " + fixed(kMaxSenderP99Ms, 0) + " ms", met(measured && sender->cpu_p99_ms <= kMaxSenderP99Ms)});
  }
  targets.add_row({"JS heap growth, lap 2 to " + std::to_string(f.laps.size()), fixed(100 * f.heap_growth(), 1) + " %",
                   "≤ " + fixed(100 * kMaxGrowth, 0) + " %", met(f.heap_growth() <= kMaxGrowth)});
  targets.add_row({"WASM memory growth, lap 2 to " + std::to_string(f.laps.size()),
                   fixed(100 * f.wasm_growth(), 1) + " %", "≤ " + fixed(100 * kMaxGrowth, 0) + " %",
                   met(f.wasm_growth() <= kMaxGrowth)});
  return targets.markdown() +
         "\nWASM refinement: the adaptation loop with every split known along the path "
         "(spm/path_refinement.h), the orbit flown five times per run, in the page over the .pms it fetched and in "
         "the bench process (before and after the browser's run), each side's fastest run after an untimed one. First "
         "picture: navigation start to the first frame "
         "drawn with the base mesh, a fresh browser context (empty cache) per load; on the median load the page's "
         "last file was in at " +
         fixed(f.site_ms, 0) + " ms, the WASM core instantiated at " + fixed(f.core_ms, 0) +
         " ms, the viewer opened (catalogue read) at " + fixed(f.viewer_ms, 0) +
         " ms; site bytes are the page's files as resource timing counts them. Frame rate: the sender flight with "
         "its buffer changes recorded, then the same page drawing them from memory along the same cameras (no "
         "network, no core work).\n\n";
}

std::string modes_section(const WebFigures& f) {
  Table modes({{"mode", false},
               {"frames"},
               {"fps"},
               {"CPU p50 ms"},
               {"CPU p99 ms"},
               {"step p50 ms"},
               {"step p99 ms"},
               {"frame() p50 ms"},
               {"frame() p99 ms"},
               {"render() p50 ms"},
               {"faces at end"},
               {"bytes down"},
               {"settled before", false}});
  for (const ModeFlight& m : f.modes)
    modes.add_row({m.mode, std::to_string(m.frames), fixed(m.fps, 1), fixed(m.cpu_p50_ms, 2), fixed(m.cpu_p99_ms, 2),
                   fixed(m.step_p50_ms, 2), fixed(m.step_p99_ms, 2), fixed(m.core_p50_ms, 2), fixed(m.core_p99_ms, 2), fixed(m.render_p50_ms, 2), thousands(m.faces),
                   thousands(m.down_bytes), m.settled_before ? "yes" : "no"});
  return "### Each mode along the orbit\n\nFrom the first view settled (\"settled before\": within the deadline); "
         "CPU is the page's main thread's CPU time in each frame's animation-frame callback, from Chromium's "
         "tracing: all of the page's frame work (the viewer's WASM frame, the buffer updates, for the receiver its "
         "face-id pass with the pixels read back, three.js's render call, the overlay), and not the time the "
         "thread waited for a core, which on this shared machine (SwiftShader's rasterizer threads, the server) "
         "the clock would count. The rest is by the clock (performance.now): step is the viewer's frame, the "
         "buffer updates and the JS around them; frame() the viewer's frame alone (the WASM core and the binding "
         "moving its bytes); render() three.js issuing the frame's draw.\n\n" +
         modes.markdown() + "\n";
}

std::string laps_section(const WebFigures& f, double lap_seconds) {
  Table laps({{"lap"}, {"frames"}, {"JS heap", false}, {"WASM memory", false}});
  for (size_t i = 0; i < f.laps.size(); ++i)
    laps.add_row(
        {std::to_string(i + 1), std::to_string(f.laps[i].frames), mb(f.laps[i].heap_bytes), mb(f.laps[i].wasm_bytes)});
  return "### Memory over laps of a " + fixed(lap_seconds, 0) +
         "-second orbit (sender)\n\nAfter each lap, a garbage collection (CDP), then the JS heap's used size and "
         "the WASM memory's size.\n\n" +
         laps.markdown() + "\n";
}

std::string shares_table(const std::vector<ProfileShare>& shares, double total_ms, const char* title) {
  Table table({{title, false}, {"self ms"}, {"share"}});
  for (const ProfileShare& s : shares)
    table.add_row({s.name, fixed(s.ms, 0), fixed(total_ms > 0 ? 100 * s.ms / total_ms : 0, 1) + " %"});
  return table.markdown();
}

std::string profile_section(const WebFigures& f) {
  if (f.profile_categories.empty()) return "";
  return "### Where the sender flight's time goes\n\nThe sender flight once more under Chromium's sampling CPU "
         "profiler (CDP), the renderer's main thread: " +
         fixed(f.profile_flight_ms, 0) + " ms of flight, " + fixed(f.profile_step_ms, 0) +
         " ms of it the page's own frame work. Self time by part, then the busiest functions (WASM functions "
         "are unnamed in the release build).\n\n" +
         shares_table(f.profile_categories, f.profile_ms, "part") + "\n" +
         shares_table(f.profile_functions, f.profile_ms, "function") + "\n";
}

}  // namespace

std::string web_report(const WebFigures& f, double lap_seconds) {
  std::string out = targets_section(f) + modes_section(f) + laps_section(f, lap_seconds) + profile_section(f);
  if (!f.page_errors.empty()) {
    out += "Page errors:\n\n";
    for (const std::string& e : f.page_errors) out += "- " + e + "\n";
    out += "\n";
  }
  return out;
}

json figures_json(const WebFigures& f) {
  json modes = json::array(), laps = json::array();
  for (const ModeFlight& m : f.modes)
    modes.push_back({{"mode", m.mode},
                     {"frames", m.frames},
                     {"fps", m.fps},
                     {"cpu_p50_ms", m.cpu_p50_ms},
                     {"cpu_p99_ms", m.cpu_p99_ms},
                     {"cpu_frames", m.cpu_frames},
                     {"step_p50_ms", m.step_p50_ms},
                     {"step_p99_ms", m.step_p99_ms},
                     {"core_p50_ms", m.core_p50_ms},
                     {"core_p99_ms", m.core_p99_ms},
                     {"render_p50_ms", m.render_p50_ms},
                     {"faces", m.faces},
                     {"down_bytes", m.down_bytes},
                     {"settled_before", m.settled_before}});
  for (const LapMemory& l : f.laps)
    laps.push_back({{"frames", l.frames}, {"heap_bytes", l.heap_bytes}, {"wasm_bytes", l.wasm_bytes}});
  const auto shares_json = [](const std::vector<ProfileShare>& shares) {
    json out = json::array();
    for (const ProfileShare& s : shares) out.push_back({{"name", s.name}, {"ms", s.ms}});
    return out;
  };
  return {{"native_ops_per_s", f.native_ops_per_s},
          {"wasm_ops_per_s", f.wasm_ops_per_s},
          {"refine_ratio", f.refine_ratio()},
          {"first_picture_ms", f.first_picture_ms},
          {"first_picture_median_ms", f.first_picture_median_ms},
          {"model_bytes_to_first_picture", f.model_bytes},
          {"site_bytes_to_first_picture", f.site_bytes},
          {"streamed_fps", f.streamed_fps},
          {"replayed_fps", f.replayed_fps},
          {"fps_ratio", f.fps_ratio()},
          {"replay_frames", f.replay_frames},
          {"modes", modes},
          {"laps", laps},
          {"heap_growth", f.heap_growth()},
          {"wasm_growth", f.wasm_growth()},
          {"site_ms", f.site_ms},
          {"core_ms", f.core_ms},
          {"viewer_ms", f.viewer_ms},
          {"profile",
           {{"total_ms", f.profile_ms},
            {"flight_ms", f.profile_flight_ms},
            {"step_ms", f.profile_step_ms},
            {"categories", shares_json(f.profile_categories)},
            {"functions", shares_json(f.profile_functions)}}},
          {"page_errors", f.page_errors}};
}

}  // namespace pms::bench
