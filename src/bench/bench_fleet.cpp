// The "fleet" group: E11 at the scale of issue 45 — thousands of sender-driven sessions opened on one
// server and held (real fleets are mostly idle), then a growing share of them flying their own paths at
// 30 fps, each sending a VIEW only when a leaf it holds wants a split. The server runs on one core and the
// load processes (`pmstream-bench load-fleet`, load_fleet.h) on another, so the server's figures are its own:
// VIEW latency percentiles, server CPU over each step, RSS and bytes per session, and the knee, the first
// step whose VIEW p99 passes kKneeP99Ms. A group of its own: it takes minutes and wants both cores to itself.
#include <sched.h>
#include <signal.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>

#include "bench/bench.h"
#include "bench/bench_model.h"
#include "bench/latency_histogram.h"
#include "bench/line_child.h"
#include "bench/report.h"
#include "bench/serve_child.h"
#include "common/error.h"
#include "common/process_cpu.h"

namespace pms::bench {
namespace fs = std::filesystem;
using nlohmann::json;
namespace {

const char* const kDefaultModel = "dragon";
constexpr double kKneeP99Ms = 100;
constexpr uint32_t kTargetFlying = 200;     // issue 45: at least this many flying within the knee's p99
constexpr uint64_t kTargetSlackBytes = 20 << 10;  // and RSS <= model + tables + sessions x (state + this)
constexpr double kReadySeconds = 900, kStepGraceSeconds = 180;

// The first two CPUs this process may run on: the server's and the load's; nullopt with fewer.
std::optional<std::pair<int, int>> two_cores() {
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof(set), &set) != 0) return std::nullopt;
  std::vector<int> cpus;
  for (int c = 0; c < CPU_SETSIZE && cpus.size() < 2; ++c)
    if (CPU_ISSET(c, &set)) cpus.push_back(c);
  if (cpus.size() < 2) return std::nullopt;
  return std::pair{cpus[0], cpus[1]};
}

// While it lives, this thread (and so every thread and child it starts) runs on one CPU only; children
// keep the mask after it is restored, as `taskset` would give them.
class PinnedHere {
 public:
  explicit PinnedHere(std::optional<int> cpu) {
    if (!cpu) return;
    sched_getaffinity(0, sizeof(saved_), &saved_);
    cpu_set_t one;
    CPU_ZERO(&one);
    CPU_SET(*cpu, &one);
    pinned_ = sched_setaffinity(0, sizeof(one), &one) == 0;
  }
  ~PinnedHere() {
    if (pinned_) sched_setaffinity(0, sizeof(saved_), &saved_);
  }
  PinnedHere(const PinnedHere&) = delete;
  PinnedHere& operator=(const PinnedHere&) = delete;

 private:
  cpu_set_t saved_{};
  bool pinned_ = false;
};

struct FleetStep {
  uint32_t flying = 0;
  LatencyHistogram views;
  uint64_t views_sent = 0, frames = 0, frames_waiting = 0, unsatisfied = 0, failed = 0, splits = 0;
  double seconds = 0, server_cpu = 0, load_cpu = 0;
  uint64_t server_rss = 0;
};

struct FleetRun {
  uint32_t sessions = 0, processes = 0;
  std::optional<std::pair<int, int>> cores;
  double open_seconds = 0;
  LatencyHistogram first_views;
  uint64_t open_failed = 0;
  ServeStats idle_server, held_server, stopped;
  uint64_t mapped_bytes = 0, table_bytes = 0, splits_received = 0, failed = 0;
  std::vector<std::string> failures;
  std::vector<FleetStep> steps;
  std::optional<uint32_t> knee;
  std::string error;
};

uint32_t share(uint32_t total, uint32_t processes, uint32_t p) {
  return total / processes + (p < total % processes ? 1 : 0);
}

std::vector<std::unique_ptr<LineChild>> start_load(const BenchContext& context, const BenchModel& m, uint16_t port,
                                                   const std::vector<uint32_t>& flying) {
  const BenchOptions& o = context.options;
  const std::string self = fs::read_symlink("/proc/self/exe").string();
  std::vector<std::unique_ptr<LineChild>> load;
  uint32_t first = 0;
  for (uint32_t p = 0; p < o.fleet_processes; ++p) {
    std::string steps;
    for (uint32_t f : flying) {
      if (!steps.empty()) steps += ',';
      steps += std::to_string(share(f, o.fleet_processes, p));
    }
    const uint32_t sessions = share(o.fleet_sessions, o.fleet_processes, p);
    load.push_back(std::make_unique<LineChild>(
        "load-fleet", std::vector<std::string>{self, "load-fleet", "--pms", m.pms.string(), "--port", std::to_string(port),
                                               "--sessions", std::to_string(sessions), "--first", std::to_string(first),
                                               "--flying", steps, "--step-seconds",
                                               std::to_string(o.fleet_step_seconds)}));
    first += sessions;
  }
  return load;
}

void add_failures(FleetRun& run, const json& line) {
  for (const json& f : line.value("failures", json::array()))
    if (run.failures.size() < 5) run.failures.push_back(f.get<std::string>());
}

FleetStep run_step(FleetRun& run, ServeChild& server, std::vector<std::unique_ptr<LineChild>>& load,
                   double step_seconds) {
  FleetStep step;
  std::vector<double> load_cpu;
  for (auto& l : load) load_cpu.push_back(process_cpu_seconds(l->pid()));
  const ServeStats before = server.stats();
  for (auto& l : load) l->send_signal(SIGUSR1, "SIGUSR1");
  for (size_t p = 0; p < load.size(); ++p) {
    const json line = load[p]->next_line("step", step_seconds + kStepGraceSeconds);
    if (line.contains("error")) fail("load-fleet", line["error"].get<std::string>());
    step.flying += line["flying"].get<uint32_t>();
    step.views.merge(LatencyHistogram::from_json(line["views"]));
    step.views_sent += line["views_sent"].get<uint64_t>();
    step.frames += line["frames"].get<uint64_t>();
    step.frames_waiting += line["frames_waiting"].get<uint64_t>();
    step.unsatisfied += line["unsatisfied"].get<uint64_t>();
    step.failed += line["failed"].get<uint64_t>();
    step.splits += line["splits"].get<uint64_t>();
    step.load_cpu += process_cpu_seconds(load[p]->pid()) - load_cpu[p];
    add_failures(run, line);
  }
  const ServeStats after = server.stats();
  step.seconds = after.uptime_s - before.uptime_s;
  step.server_cpu = after.cpu_s - before.cpu_s;
  step.server_rss = after.rss_bytes;
  return step;
}

void run_fleet(const BenchContext& context, const BenchModel& m, FleetRun& run) {
  const BenchOptions& o = context.options;
  run.sessions = o.fleet_sessions;
  run.processes = o.fleet_processes;
  run.cores = two_cores();
  run.mapped_bytes = fs::file_size(m.pms);
  std::optional<ServeChild> server;
  {
    const PinnedHere pinned(run.cores ? std::optional(run.cores->first) : std::nullopt);
    // One I/O thread on its one core; idle viewers stay connected however long the steps take.
    server.emplace(context.pmstream_exe,
                   std::vector<std::string>{m.pms.string(), "--max-sessions", std::to_string(o.fleet_sessions + 16),
                                            "--threads", "1", "--idle-timeout-ms", "3600000", "--preload", "sender"});
  }
  run.idle_server = server->stats();
  run.table_bytes = run.idle_server.line.value("table_bytes", uint64_t(0));
  std::vector<std::unique_ptr<LineChild>> load;
  {
    const PinnedHere pinned(run.cores ? std::optional(run.cores->second) : std::nullopt);
    load = start_load(context, m, server->port(), o.fleet_flying);
  }
  for (auto& l : load) {
    const json ready = l->next_line("ready", kReadySeconds);
    run.open_seconds = std::max(run.open_seconds, ready["seconds"].get<double>());
    run.first_views.merge(LatencyHistogram::from_json(ready["first_views"]));
    run.open_failed += ready["failed"].get<uint64_t>();
    add_failures(run, ready);
  }
  run.held_server = server->stats();
  std::fprintf(stderr, "bench: fleet: %u sessions held, server RSS %.0f MB\n", run.sessions,
               double(run.held_server.rss_bytes) / 1048576);
  for (size_t k = 0; k < o.fleet_flying.size() && !run.knee; ++k) {
    run.steps.push_back(run_step(run, *server, load, o.fleet_step_seconds));
    const FleetStep& s = run.steps.back();
    std::fprintf(stderr, "bench: fleet: %u flying, VIEW p99 %.1f ms, server CPU %.2f cores\n", s.flying,
                 s.views.percentile(0.99), s.server_cpu / std::max(s.seconds, 1e-9));
    if (s.views.percentile(0.99) > kKneeP99Ms) run.knee = s.flying;
  }
  for (auto& l : load) {
    l->send_signal(SIGTERM, "SIGTERM");
    const json done = l->next_line("done", 60);
    run.splits_received += done["splits"].get<uint64_t>();
    run.failed += done["failed"].get<uint64_t>();
    l->wait_ok(60);
  }
  run.stopped = server->stop();
}

Table step_table() {
  return Table({{"flying", true},
                {"VIEWs", true},
                {"VIEWs/s", true},
                {"p50 ms", true},
                {"p95 ms", true},
                {"p99 ms", true},
                {"max ms", true},
                {"frames waiting", true},
                {"unsatisfied", true},
                {"failed", true},
                {"server CPU (cores)", true},
                {"load CPU (cores)", true},
                {"server RSS MB", true}});
}

std::string percent_of_frames(const FleetStep& s) {
  return fixed(100.0 * double(s.frames_waiting) / double(std::max<uint64_t>(s.frames, 1)), 1) + " %";
}

std::string mb(uint64_t bytes) { return fixed(double(bytes) / 1048576, 1); }

uint64_t rss_bound(const FleetRun& run) {
  return run.mapped_bytes + run.table_bytes + uint64_t(run.sessions) * (run.stopped.peak_state_bytes + kTargetSlackBytes);
}

uint64_t peak_rss(const FleetRun& run) {
  uint64_t peak = run.held_server.rss_bytes;
  for (const FleetStep& s : run.steps) peak = std::max(peak, s.server_rss);
  return peak;
}

std::string summary(const FleetRun& run, const std::string& model) {
  const uint64_t per_session =
      (run.held_server.rss_bytes - std::min(run.held_server.rss_bytes, run.idle_server.rss_bytes)) / run.sessions;
  uint32_t best = 0;
  for (const FleetStep& s : run.steps)
    if (s.views.percentile(0.99) <= kKneeP99Ms) best = std::max(best, s.flying);
  std::string text;
  text += "- " + std::to_string(run.sessions) + " sessions on " + model + " from " + std::to_string(run.processes) +
          " load processes; " +
          (run.cores ? "server pinned to CPU " + std::to_string(run.cores->first) + ", load processes to CPU " +
                           std::to_string(run.cores->second)
                     : std::string("one CPU only: server and load share it (not pinned)")) +
          "\n";
  text += "- opening: " + fixed(run.open_seconds, 1) + " s for all, first VIEW (from the base mesh) p50 " +
          fixed(run.first_views.percentile(0.5), 1) + " ms, p99 " + fixed(run.first_views.percentile(0.99), 1) +
          " ms, " + std::to_string(run.open_failed) + " failed\n";
  text += "- server RSS: " + mb(run.idle_server.rss_bytes) + " MB with the model mapped and its tables built, " +
          mb(run.held_server.rss_bytes) + " MB with every session held idle: " + thousands(per_session) +
          " bytes per session; peak " + mb(peak_rss(run)) + " MB\n";
  text += "- RSS bound: mapped model " + mb(run.mapped_bytes) + " MB + tables " + mb(run.table_bytes) + " MB + " +
          std::to_string(run.sessions) + " × (peak session state " + thousands(run.stopped.peak_state_bytes) +
          " B + 20 KB) = " + mb(rss_bound(run)) + " MB: " + (peak_rss(run) <= rss_bound(run) ? "met" : "**missed**") +
          "\n";
  text += "- knee (VIEW p99 > " + fixed(kKneeP99Ms, 0) + " ms): " +
          (run.knee ? std::to_string(*run.knee) + " flying" : "not reached") + "; most flying within it: " +
          std::to_string(best) + " (target ≥ " + std::to_string(kTargetFlying) + ": " +
          (best >= kTargetFlying ? "met" : "**missed**") + ")\n";
  text += "- splits: " + thousands(run.stopped.splits_sent) + " sent, " + thousands(run.splits_received) +
          " received and checked against the model; " + std::to_string(run.failed) + " sessions failed\n";
  for (const std::string& f : run.failures) text += "  - failure: " + f + "\n";
  return text;
}

json step_json(const FleetStep& s) {
  return {{"flying", s.flying},
          {"views", s.views.count()},
          {"views_sent", s.views_sent},
          {"p50_ms", s.views.percentile(0.5)},
          {"p95_ms", s.views.percentile(0.95)},
          {"p99_ms", s.views.percentile(0.99)},
          {"max_ms", s.views.max_ms()},
          {"frames", s.frames},
          {"frames_waiting", s.frames_waiting},
          {"unsatisfied", s.unsatisfied},
          {"failed", s.failed},
          {"splits", s.splits},
          {"seconds", s.seconds},
          {"server_cpu_seconds", s.server_cpu},
          {"load_cpu_seconds", s.load_cpu},
          {"server_rss_bytes", s.server_rss}};
}

json run_json(const FleetRun& run) {
  json steps = json::array();
  for (const FleetStep& s : run.steps) steps.push_back(step_json(s));
  return {{"sessions", run.sessions},
          {"processes", run.processes},
          {"pinned", run.cores.has_value()},
          {"open_seconds", run.open_seconds},
          {"first_view_p50_ms", run.first_views.percentile(0.5)},
          {"first_view_p99_ms", run.first_views.percentile(0.99)},
          {"open_failed", run.open_failed},
          {"server_rss_idle_bytes", run.idle_server.rss_bytes},
          {"server_rss_held_bytes", run.held_server.rss_bytes},
          {"server_peak_rss_bytes", peak_rss(run)},
          {"mapped_model_bytes", run.mapped_bytes},
          {"table_bytes", run.table_bytes},
          {"peak_session_state_bytes", run.stopped.peak_state_bytes},
          {"rss_bound_bytes", rss_bound(run)},
          {"knee_flying", run.knee ? json(*run.knee) : json(nullptr)},
          {"splits_sent", run.stopped.splits_sent},
          {"splits_received", run.splits_received},
          {"failed", run.failed},
          {"failures", run.failures},
          {"steps", steps}};
}

}  // namespace

void run_fleet_group(BenchContext& context) {
  std::string section = "## fleet: E11 at scale, many sessions held, a growing share flying\n\n";
  if (skipped_without_models(context, section)) return;
  const std::string name = context.options.models.empty() ? kDefaultModel : context.options.models.front();
  const BenchModel m = prepare_model(context, name);
  FleetRun run;
  json out = {{"command", context.options.command_line}, {"machine", machine_json()}, {"model", name}};
  try {
    run_fleet(context, m, run);
  } catch (const Error& e) {
    run.error = e.what();
    context.failures.push_back("fleet: " + run.error);
  }
  Table table = step_table();
  for (const FleetStep& s : run.steps)
    table.add_row({std::to_string(s.flying), thousands(s.views.count()),
                   fixed(double(s.views.count()) / std::max(s.seconds, 1e-9), 0), fixed(s.views.percentile(0.5), 2),
                   fixed(s.views.percentile(0.95), 2), fixed(s.views.percentile(0.99), 2), fixed(s.views.max_ms(), 1),
                   percent_of_frames(s), thousands(s.unsatisfied), thousands(s.failed),
                   fixed(s.server_cpu / std::max(s.seconds, 1e-9), 2), fixed(s.load_cpu / std::max(s.seconds, 1e-9), 2),
                   mb(s.server_rss)});
  const std::string text = run.error.empty() ? summary(run, name) : "- **not measured**: " + run.error + "\n";
  std::printf("\nE11 fleet on %s\n%s\n%s", name.c_str(), table.markdown().c_str(), text.c_str());
  std::fflush(stdout);
  section += "### E11 fleet: " + std::to_string(context.options.fleet_sessions) + " sessions on " + name + ", " +
             fixed(context.options.fleet_step_seconds, 0) + " s a step\n\n" + table.markdown() + "\n" + text +
             "\nEach step flies the first sessions of each load process at 30 fps along their own paths (orbits and "
             "scans, own phases); a session sends a VIEW only when a leaf it holds wants a split (qrefine on the "
             "server's own criteria), one at a time, and a step ends with each flown session settling on its last "
             "camera (\"unsatisfied\": still wanting splits after 4 VIEWs). Latency = VIEW sent to its final batch "
             "(2 % buckets). \"frames waiting\" = frames a viewer flew on while its VIEW was unanswered. Server CPU "
             "= its cpu_s over the step (SIGUSR1 before and after) per wall second; load CPU = the load processes' "
             "over the same window, on their own core.\n\n";
  out["run"] = run_json(run);
  if (!run.error.empty()) out["error"] = run.error;
  write_text_file(context.options.out_dir / "fleet.json", out.dump(2) + "\n");
  context.report += section;
}

}  // namespace pms::bench
