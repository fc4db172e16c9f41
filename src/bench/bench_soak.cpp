// The "soak" group (requirement 8): N clients on one model (dragon) for M minutes against one
// `pmstream serve --json` process. Each client flies its own path at a steady rate, drops its connection
// every 30–90 s and comes back resuming or as a new viewer (soak_client.h). Every 10 s the server is
// asked for its counters (SIGUSR1); the report has a table per minute (latency, sessions, failures,
// server RSS), the RSS growth after the first minute, the p99 ratio of the last minute to the first,
// a PNG of RSS over time and soak.json. docs/internals.md says what each figure means.
#include <algorithm>
#include <atomic>
#include <cstdio>
#include <future>
#include <optional>
#include <thread>

#include "apps/percentile.h"
#include "bench/bench.h"
#include "bench/bench_model.h"
#include "bench/gnuplot.h"
#include "bench/report.h"
#include "bench/serve_child.h"
#include "bench/soak_client.h"
#include "common/error.h"

namespace pms::bench {
using app::PathKind;
using app::percentile;
namespace fs = std::filesystem;
using nlohmann::json;
using Clock = std::chrono::steady_clock;
namespace {

const char* const kDefaultModel = "dragon";
constexpr float kTolerance = 1;
constexpr uint32_t kOrbitFrames = 240, kScanFrames = 120;  // a lap in 60 s at 4 frames per second
constexpr uint32_t kSampleSeconds = 10;
constexpr double kStartSpreadSeconds = 10;  // clients start one after another, not as one thundering herd
constexpr uint64_t kSeed = 2005;
// Requirement 8's target, stated for 100 clients × 10 minutes on dragon.
constexpr double kTargetRssGrowth = 0.01, kTargetP99Ratio = 1.5;

struct Sample {
  double t_s = 0;
  ServeStats stats;
};

struct SoakRun {
  std::vector<Sample> samples;
  std::vector<SoakClientLog> clients;
  std::vector<std::string> paths;
  std::optional<ServeStats> stopped;
  std::string server_error;  // the server did not report (a missing or unparsable line): figures are missing
  std::string server_log;
};

std::vector<SoakClientPlan> plan_clients(const BenchModel& m, uint16_t port, uint32_t clients, uint32_t minutes,
                                         Clock::time_point t0, const std::vector<Camera>& orbit,
                                         const std::vector<Camera>& scan, const std::shared_future<void>& release) {
  std::vector<SoakClientPlan> plans(clients);
  for (uint32_t i = 0; i < clients; ++i) {
    SoakClientPlan& p = plans[i];
    p.port = port;
    p.model = m.name;
    p.data = &m.served->model();
    p.path = SoakPath::of_client(i, orbit, scan);
    p.seed = kSeed + i;
    p.t0 = t0;
    p.start = t0 + std::chrono::duration_cast<Clock::duration>(
                       std::chrono::duration<double>(kStartSpreadSeconds * double(i) / double(clients)));
    p.end = t0 + std::chrono::minutes(minutes);
    p.tolerance = kTolerance;
    p.release = release;
  }
  return plans;
}

SoakRun run_soak(const BenchContext& context, const BenchModel& m, uint32_t clients, uint32_t minutes) {
  SoakRun run;
  std::optional<ServeChild> server;
  try {
    server.emplace(context.pmstream_exe,
                   std::vector<std::string>{m.pms.string(), "--max-sessions", std::to_string(clients + 16)});
    run.samples.push_back({0, server->stats()});  // the model mapped, no session yet
  } catch (const Error& e) {
    run.server_error = e.what();
    return run;
  }
  const std::vector<Camera> orbit = path_of(m, PathKind::orbit, kOrbitFrames);
  const std::vector<Camera> scan = path_of(m, PathKind::scan, kScanFrames);
  const Clock::time_point t0 = Clock::now();
  std::promise<void> sampled;
  const std::vector<SoakClientPlan> plans =
      plan_clients(m, server->port(), clients, minutes, t0, orbit, scan, sampled.get_future().share());
  run.clients.resize(clients);
  std::vector<std::thread> threads;
  for (uint32_t i = 0; i < clients; ++i) {
    run.paths.push_back(plans[i].path.name);
    threads.emplace_back([&, i] { run.clients[i] = run_soak_client(plans[i], minutes); });
  }
  for (uint32_t k = 1; k <= minutes * 60 / kSampleSeconds; ++k) {
    std::this_thread::sleep_until(t0 + std::chrono::seconds(k * kSampleSeconds));
    try {
      run.samples.push_back({std::chrono::duration<double>(Clock::now() - t0).count(), server->stats()});
    } catch (const Error& e) {
      run.server_error = e.what();
      break;
    }
    const ServeStats& s = run.samples.back().stats;
    std::fprintf(stderr, "bench: soak %u:%02u of %u:00, %llu sessions, server RSS %.1f MB\n", k * kSampleSeconds / 60,
                 k * kSampleSeconds % 60, minutes, (unsigned long long)s.sessions_active,
                 double(s.rss_bytes) / 1048576);
  }
  sampled.set_value();
  for (std::thread& t : threads) t.join();
  if (run.server_error.empty()) {
    try {
      run.stopped = server->stop();
      run.server_log = server->log();
    } catch (const Error& e) {
      run.server_error = e.what();
    }
  }
  return run;
}

// ---- the report ----------------------------------------------------------------------------------------

struct MinuteTotals {
  std::vector<double> view_ms, open_ms;
  uint64_t fresh = 0, resumes = 0, reconnects = 0, failures = 0, splits = 0;
};

// What the report and soak.json say, from the clients' logs and the server's samples.
struct SoakFigures {
  std::vector<MinuteTotals> minutes;
  uint64_t failures = 0, server_faults = 0, min_frames = 0, splits_received = 0;
  const Sample* first = nullptr;                // the sample at the end of minute 1
  const Sample* last = nullptr;                 // the last sample, at the end of the soak
  std::optional<double> rss_growth, p99_ratio;  // both need a minute after the first
  // Minute 1 also holds every client's first session, so the last minute is compared with minute 2 too.
  std::optional<double> p99_ratio_to_second;  // needs a third minute
  double p99_first = 0, p99_second = 0, p99_last = 0;
  bool no_failures = false;
};

// The sample taken at the end of minute m (0: before any client); nullptr when the server stopped
// reporting before.
const Sample* sample_at_minute(const SoakRun& run, uint32_t m) {
  const size_t index = size_t(m) * 60 / kSampleSeconds;
  return index < run.samples.size() ? &run.samples[index] : nullptr;
}

SoakFigures summarize(const SoakRun& run, uint32_t minutes) {
  SoakFigures f;
  f.minutes.resize(minutes);
  f.min_frames = run.clients.empty() ? 0 : UINT64_MAX;
  for (const SoakClientLog& c : run.clients) {
    f.min_frames = std::min(f.min_frames, c.frames);
    for (uint32_t m = 0; m < minutes && m < c.minutes.size(); ++m) {
      const SoakMinute& s = c.minutes[m];
      MinuteTotals& t = f.minutes[m];
      t.view_ms.insert(t.view_ms.end(), s.view_ms.begin(), s.view_ms.end());
      t.open_ms.insert(t.open_ms.end(), s.open_ms.begin(), s.open_ms.end());
      t.fresh += s.fresh;
      t.resumes += s.resumes;
      t.reconnects += s.reconnects;
      t.failures += s.failures;
      t.splits += s.splits;
      f.failures += s.failures;
      f.splits_received += s.splits;
    }
  }
  if (run.stopped)
    f.server_faults = run.stopped->sessions_failed + run.stopped->protocol_errors + run.stopped->sessions_timed_out +
                      run.stopped->sessions_refused;
  f.no_failures = f.failures == 0 && f.server_faults == 0 && run.server_error.empty();
  f.first = sample_at_minute(run, 1);
  f.last = sample_at_minute(run, minutes);
  f.p99_first = percentile(f.minutes.front().view_ms, 0.99);
  f.p99_last = percentile(f.minutes.back().view_ms, 0.99);
  if (minutes >= 2 && f.first && f.last && f.first->stats.rss_bytes > 0)
    f.rss_growth =
        (double(f.last->stats.rss_bytes) - double(f.first->stats.rss_bytes)) / double(f.first->stats.rss_bytes);
  if (minutes >= 2 && f.p99_first > 0) f.p99_ratio = f.p99_last / f.p99_first;
  if (minutes >= 3) f.p99_second = percentile(f.minutes[1].view_ms, 0.99);
  if (minutes >= 3 && f.p99_second > 0) f.p99_ratio_to_second = f.p99_last / f.p99_second;
  return f;
}

double mb(uint64_t bytes) { return double(bytes) / (1024.0 * 1024.0); }

std::string met(const std::optional<bool>& ok) { return !ok ? "n/a" : *ok ? "met" : "**missed**"; }

std::optional<bool> within(const std::optional<double>& value, double limit) {
  if (!value) return std::nullopt;
  return *value <= limit;
}

json as_json(const std::optional<double>& value) { return value ? json(*value) : json(); }
json as_json(const std::optional<bool>& value) { return value ? json(*value) : json(); }

Table minute_table(const SoakRun& run, const SoakFigures& f, json& rows) {
  Table table({{"minute", true},
               {"VIEWs", true},
               {"p50 ms", true},
               {"p99 ms", true},
               {"OPEN p99 ms", true},
               {"new sessions", true},
               {"resumes", true},
               {"failed", true},
               {"vsplits", true},
               {"sessions active", true},
               {"server RSS MB", true},
               {"server CPU s", true}});
  for (uint32_t m = 1; m <= f.minutes.size(); ++m) {
    const MinuteTotals& t = f.minutes[m - 1];
    const Sample* end = sample_at_minute(run, m);
    const Sample* begin = sample_at_minute(run, m - 1);
    const std::string none = "no report";
    table.add_row({std::to_string(m), thousands(t.view_ms.size()), fixed(percentile(t.view_ms, 0.5), 2),
                   fixed(percentile(t.view_ms, 0.99), 2), fixed(percentile(t.open_ms, 0.99), 2), thousands(t.fresh),
                   thousands(t.resumes), thousands(t.failures), thousands(t.splits),
                   end ? thousands(end->stats.sessions_active) : none, end ? fixed(mb(end->stats.rss_bytes), 1) : none,
                   end && begin ? fixed(end->stats.cpu_s - begin->stats.cpu_s, 2) : none});
    json row = {{"minute", m},
                {"views", t.view_ms.size()},
                {"p50_ms", percentile(t.view_ms, 0.5)},
                {"p99_ms", percentile(t.view_ms, 0.99)},
                {"open_p99_ms", percentile(t.open_ms, 0.99)},
                {"new_sessions", t.fresh},
                {"resumes", t.resumes},
                {"reconnects", t.reconnects},
                {"failures", t.failures},
                {"splits", t.splits}};
    if (end) row.update({{"sessions_active", end->stats.sessions_active}, {"rss_bytes", end->stats.rss_bytes}});
    rows.push_back(row);
  }
  return table;
}

std::string counted_faults(const SoakRun& run) {
  if (!run.stopped) return "nothing (no stopped line)";
  const ServeStats& s = *run.stopped;
  return std::to_string(s.sessions_failed) + " failed, " + std::to_string(s.protocol_errors) + " protocol errors, " +
         std::to_string(s.sessions_timed_out) + " timed out, " + std::to_string(s.sessions_refused) + " refused";
}

std::string rss_of(const Sample* s) { return s ? fixed(mb(s->stats.rss_bytes), 1) + " MB" : "no report"; }

std::string summary(const SoakRun& run, const SoakFigures& f, const std::string& model, uint32_t clients,
                    uint32_t minutes) {
  const std::string na = "n/a (needs 2+ minutes)";
  std::string text = "- " + std::to_string(clients) + " protocol clients × " + std::to_string(minutes) + " min on " +
                     model + ", τ = " + fixed(kTolerance, 0) + " px, " + fixed(kSoakFramesPerSecond, 0) +
                     " VIEWs per second each (orbits and scans, each from its own phase), a dropped connection every "
                     "30–90 s, then a resume or a new session (even odds); seed " +
                     std::to_string(kSeed) + ".\n";
  text += "- failed sessions: " + std::to_string(f.failures) + " seen by clients; the server counted " +
          counted_faults(run) + "; fewest frames of a client: " + std::to_string(f.min_frames) + ".\n";
  if (run.stopped)
    text += "- vsplits: the server sent " + thousands(run.stopped->splits_sent) + ", the clients received " +
            thousands(f.splits_received) + " (each checked to extend a leaf its client held); server CPU " +
            fixed(run.stopped->cpu_s, 1) + " s, peak RSS " + fixed(mb(run.stopped->peak_rss_bytes), 1) +
            " MB, peak session state " + thousands(run.stopped->peak_state_bytes) + " bytes, longest turn " +
            thousands(run.stopped->longest_turn_us) + " µs.\n";
  text += "- server RSS at the end of minute 1: " + rss_of(f.first) + ", at the end: " + rss_of(f.last) + ", growth " +
          (f.rss_growth ? fixed(100 * *f.rss_growth, 2) + " %" : na) + ".\n";
  text += "- p99 latency, last minute / first: " + fixed(f.p99_last, 2) + " / " + fixed(f.p99_first, 2) +
          " ms = " + (f.p99_ratio ? fixed(*f.p99_ratio, 2) : na) +
          "; last / minute 2 (minute 1 also holds every client's " +
          "first session): " + (f.p99_ratio_to_second ? fixed(*f.p99_ratio_to_second, 2) : "n/a (needs 3+ minutes)") +
          ".\n";
  text +=
      "- target (requirement 8, stated for 100 clients × 10 min on dragon): RSS growth after the first minute "
      "≤ 1 %: " +
      met(within(f.rss_growth, kTargetRssGrowth)) + "; 0 failed sessions: " + met(f.no_failures) +
      "; p99 in the last minute ≤ 1.5× the first: " + met(within(f.p99_ratio, kTargetP99Ratio)) + ".\n";
  if (!run.server_error.empty()) text += "- **no server report**: " + run.server_error + "\n";
  const size_t log_lines = size_t(std::count(run.server_log.begin(), run.server_log.end(), '\n'));
  text += "- server log (stderr): " + std::to_string(log_lines) + " lines" +
          (log_lines ? ", the first: `" + run.server_log.substr(0, run.server_log.find('\n')) + "`" : std::string()) +
          ".\n";
  for (uint32_t i = 0; i < run.clients.size(); ++i)
    for (const std::string& failure : run.clients[i].failures)
      text += "- client " + std::to_string(i) + " failed at " + failure + "\n";
  return text;
}

// soak-rss.png: RSS and sessions over time; the note the report prints in its place.
std::string plot_rss(const SoakRun& run, const fs::path& out_dir, const std::string& title) {
  Plot plot;
  plot.title = title;
  plot.xlabel = "minutes";
  plot.ylabel = "server RSS MB";
  plot.y2label = "sessions active";
  PlotSeries rss{"server RSS (MB)", {}, {}, false}, active{"sessions active", {}, {}, true};
  for (const Sample& s : run.samples) {
    rss.x.push_back(s.t_s / 60);
    rss.y.push_back(mb(s.stats.rss_bytes));
    active.x.push_back(s.t_s / 60);
    active.y.push_back(double(s.stats.sessions_active));
  }
  plot.series = {rss, active};
  const std::string error = plot_png(plot, out_dir / "soak-rss.png");
  return error.empty() ? "![server RSS over time](soak-rss.png)" : "(no plot: " + error + ")";
}

json soak_json(const BenchContext& context, const SoakRun& run, const SoakFigures& f, const std::string& model,
               json minutes) {
  json samples = json::array(), clients = json::array();
  for (const Sample& s : run.samples) samples.push_back({{"t_s", s.t_s}, {"stats", s.stats.line}});
  for (uint32_t i = 0; i < run.clients.size(); ++i) {
    uint64_t failures = 0, splits = 0;
    for (const SoakMinute& s : run.clients[i].minutes) {
      failures += s.failures;
      splits += s.splits;
    }
    clients.push_back({{"client", i},
                       {"path", run.paths[i]},
                       {"frames", run.clients[i].frames},
                       {"failures", failures},
                       {"splits", splits},
                       {"failure_texts", run.clients[i].failures}});
  }
  return {{"command", context.options.command_line},
          {"machine", machine_json()},
          {"model", model},
          {"clients", context.options.soak_clients},
          {"minutes", context.options.soak_minutes},
          {"frames_per_second", kSoakFramesPerSecond},
          {"tolerance_px", kTolerance},
          {"seed", kSeed},
          {"samples", samples},
          {"per_minute", minutes},
          {"per_client", clients},
          {"failures", f.failures},
          {"server_faults", f.server_faults},
          {"splits_received", f.splits_received},
          {"rss_growth_after_first_minute", as_json(f.rss_growth)},
          {"p99_last_over_first", as_json(f.p99_ratio)},
          {"p99_last_over_second", as_json(f.p99_ratio_to_second)},
          {"stopped", run.stopped ? run.stopped->line : json()},
          {"server_error", run.server_error},
          {"server_log", run.server_log},
          {"target",
           {{"rss_growth_max", kTargetRssGrowth},
            {"p99_ratio_max", kTargetP99Ratio},
            {"rss_growth_met", as_json(within(f.rss_growth, kTargetRssGrowth))},
            {"no_failures_met", f.no_failures},
            {"p99_ratio_met", as_json(within(f.p99_ratio, kTargetP99Ratio))}}}};
}

}  // namespace

void run_soak_group(BenchContext& context) {
  std::string section = "## soak: many clients for minutes, with reconnects and resumes\n\n";
  if (skipped_without_models(context, section)) return;
  const uint32_t clients = context.options.soak_clients, minutes = context.options.soak_minutes;
  const std::string name = context.options.models.empty() ? kDefaultModel : context.options.models.back();
  const BenchModel m = prepare_model(context, name);
  std::fprintf(stderr, "bench: soak, %u clients × %u min on %s\n", clients, minutes, name.c_str());
  const SoakRun run = run_soak(context, m, clients, minutes);
  if (!run.server_error.empty()) context.failures.push_back("soak: " + run.server_error);
  const SoakFigures figures = summarize(run, minutes);
  json minute_rows = json::array();
  const Table table = minute_table(run, figures, minute_rows);
  const std::string text =
      table.markdown() + "\n" + summary(run, figures, name, clients, minutes) + "\n" +
      plot_rss(run, context.options.out_dir, "soak: " + std::to_string(clients) + " clients on " + name) + "\n\n";
  std::printf("\nsoak: %u clients × %u min on %s\n%s", clients, minutes, name.c_str(), text.c_str());
  std::fflush(stdout);
  write_text_file(context.options.out_dir / "soak.json",
                  soak_json(context, run, figures, name, std::move(minute_rows)).dump(2) + "\n");
  context.report += section + text;
  run_failover_figure(context);
}

}  // namespace pms::bench
