// The viewer group's idle-time experiment (kim-lee-kobbelt §9; issue 47's target): the sender-driven viewer
// free-running at the display rate along the orbit, two laps, over a delayed link (delay_proxy.h; the rate and
// the round trip are the issue's, set below), with `stream --ahead` and without, side by side: the share of frames whose view is satisfied, bytes down and up,
// the splits that came ahead, and whether the settled mesh is the lock-step one.
#include <array>
#include <cstdio>

#include "apps/camera_json.h"
#include "bench/bench.h"
#include "bench/bench_model.h"
#include "bench/bench_refine.h"
#include "bench/child_process.h"
#include "bench/delay_proxy.h"
#include "bench/report.h"
#include "bench/serve_child.h"
#include "io/mesh.h"

namespace pms::bench {
namespace {

using nlohmann::json;

constexpr uint32_t kFrames = 90;  // per lap: three seconds at 30 fps
constexpr uint32_t kLaps = 2;
constexpr uint32_t kFps = 30;
constexpr uint32_t kRoundTripMs = 50;
// The camera this many frames on: a round trip (1.5 frames) and the server's work, with room to spare.
constexpr uint32_t kAheadFrames = 6;
constexpr double kMinGainPoints = 20;    // the target: satisfied share, with against without
constexpr double kMaxExtraBytes = 0.10;  // at most this much more down over the two laps

struct Flight {
  std::string error;
  json out;
  std::vector<PositionedTriangle> settled;
};

Flight fly(const BenchContext& context, const std::string& server, const std::string& model,
           const std::filesystem::path& path, uint32_t fps, uint32_t ahead, const std::filesystem::path& mesh) {
  std::vector<std::string> argv = {context.pmstream_exe, "stream", "--server", server,         "--mode",
                                   "sender",             "--model", model,  "--path", path.string(),
                                   "--laps",             std::to_string(kLaps), "--json", "--save-mesh", mesh.string()};
  if (fps) argv.insert(argv.end(), {"--fps", std::to_string(fps)});
  if (ahead) argv.insert(argv.end(), {"--ahead", std::to_string(ahead)});
  ChildOptions options;
  options.timeout_seconds = 600;
  const ChildResult result = run_child(argv, options);
  Flight flight;
  if (!result.ok()) {
    flight.error = result.failure();
    return flight;
  }
  flight.out = json::parse(result.out);
  const Mesh settled = load_mesh(mesh.string());
  flight.settled = positioned_triangles(settled.positions, settled.indices);
  return flight;
}

double satisfied_share(const json& frames) {
  size_t satisfied = 0;
  for (const json& f : frames) satisfied += f.value("satisfied", false);
  return frames.empty() ? 0 : 100.0 * double(satisfied) / double(frames.size());
}

}  // namespace

void run_idle_time_group(BenchContext& context) {
  std::string section = "## idle: sender-driven idle time (kim-lee-kobbelt §9) at 30 fps over a 50 ms round trip\n\n";
  if (skipped_without_models(context, section)) return;
  const std::string model = context.options.quick ? "bunny" : "dragon";
  const BenchModel m = prepare_model(context, model);
  ServeChild server(context.pmstream_exe, {m.pms.string(), "--preload", "all"});
  const DelayProxy relay(server.port(), std::chrono::milliseconds(kRoundTripMs / 2));
  const std::string address = "127.0.0.1:" + std::to_string(relay.port());
  const std::filesystem::path path = context.temp_dir / (model + "-idle-orbit.json");
  app::save_path(path.string(), path_of(m, app::PathKind::orbit, kFrames));
  section += "Model " + model + ", the orbit of " + std::to_string(kFrames) + " frames flown " + std::to_string(kLaps) +
             " times at " + std::to_string(kFps) + " fps (`pmstream stream --mode sender --fps 30 --laps 2`), τ = 1 px, "
             "through a relay holding each direction's bytes " + std::to_string(kRoundTripMs / 2) +
             " ms; the server's defaults (`--ahead-budget` 1 MiB a session). \"ahead\" adds `--ahead " +
             std::to_string(kAheadFrames) + "`. A frame is satisfied when no VIEW is on the wire and its view "
             "lacks nothing. Targets: ≥ " + fixed(kMinGainPoints, 0) + " points more frames satisfied, ≤ +" +
             fixed(100 * kMaxExtraBytes, 0) + " % bytes down. Frame timing depends on the machine: rerun on a quiet one.\n\n";
  std::fprintf(stderr, "bench: idle, lock-step\n");
  const Flight lock_step =
      fly(context, "127.0.0.1:" + std::to_string(server.port()), model, path, 0, 0, context.temp_dir / "idle-lock.ply");
  Table table({{"run", false},
               {"frames satisfied %"},
               {"bytes down"},
               {"bytes up"},
               {"AHEADs"},
               {"splits ahead"},
               {"splits"},
               {"settled = lock-step", false}});
  print_now("\n" + section + table.header());
  json runs = json::array();
  std::array<Flight, 2> flights;
  for (const uint32_t ahead : {0u, kAheadFrames}) {
    std::fprintf(stderr, "bench: idle, ahead %u\n", ahead);
    Flight& f = flights[ahead ? 1 : 0];
    f = fly(context, address, model, path, kFps, ahead, context.temp_dir / "idle-free.ply");
    const char* name = ahead ? "ahead" : "without";
    if (!f.error.empty() || !lock_step.error.empty()) {
      const std::string why = f.error.empty() ? "lock-step: " + lock_step.error : f.error;
      context.failures.push_back(std::string("idle ") + name + ": " + why);
      print_now(table.add_row({name, "failed", "", "", "", "", "", why}));
      continue;
    }
    const double share = satisfied_share(f.out["frames"]);
    const bool same = f.settled == lock_step.settled;
    print_now(table.add_row({name, fixed(share, 1), thousands(f.out.value("total_down_bytes", uint64_t(0))),
                             thousands(f.out.value("total_up_bytes", uint64_t(0))),
                             thousands(f.out.value("aheads_sent", uint64_t(0))),
                             thousands(f.out.value("ahead_vsplits", uint64_t(0))),
                             thousands(f.out.value("vsplits_received", uint64_t(0))), same ? "yes" : "no"}));
    runs.push_back({{"run", name},
                    {"ahead_frames", ahead},
                    {"satisfied_percent", share},
                    {"down_bytes", f.out.value("total_down_bytes", uint64_t(0))},
                    {"up_bytes", f.out.value("total_up_bytes", uint64_t(0))},
                    {"aheads_sent", f.out.value("aheads_sent", uint64_t(0))},
                    {"ahead_vsplits", f.out.value("ahead_vsplits", uint64_t(0))},
                    {"vsplits", f.out.value("vsplits_received", uint64_t(0))},
                    {"settled_equals_lock_step", same}});
  }
  section += table.markdown() + "\n";
  if (runs.size() == 2) {
    const double gain = runs[1]["satisfied_percent"].get<double>() - runs[0]["satisfied_percent"].get<double>();
    const double without = double(runs[0]["down_bytes"].get<uint64_t>());
    const double extra = without > 0 ? double(runs[1]["down_bytes"].get<uint64_t>()) / without - 1 : 0;
    const bool met = gain >= kMinGainPoints && extra <= kMaxExtraBytes;
    section += "Satisfied: " + fixed(gain, 1) + " points more with it; bytes down " + (extra >= 0 ? "+" : "") +
               fixed(100 * extra, 1) + " %: target " + (met ? "met" : "missed") + ".\n\n";
  }
  write_text_file(context.options.out_dir / "idle.json",
                  json{{"model", model}, {"rtt_ms", kRoundTripMs}, {"fps", kFps}, {"laps", kLaps}, {"runs", runs}}.dump(2) +
                      "\n");
  context.report += section;
}

}  // namespace pms::bench
