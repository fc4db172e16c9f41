// The "tier" group (issue 45, requirement 4): cheng-ooi's claim that a receiver-driven origin keeps nothing
// per viewer, so an ordinary HTTP cache carries the load. 100 receiver-driven viewers (client::ReceiverClient,
// lock-step, fetching blocks) fly dragon on mixed paths, several viewers a path, through Debian's nginx with
// the shipped deploy/nginx/pmstream-cache.conf in front of two `pmstream serve` origins; one origin is killed
// (SIGKILL) when the first viewer is halfway. Then the same viewers on the same paths fly sender-driven
// (client::StreamingClient) against one `serve`. The report has viewers failed, origin requests, the
// cache's hit rate (overall and from the second viewer of a path on), bytes served by the cache and by the
// origins, and the origins' CPU per split delivered beside the sender-driven server's CPU per split sent,
// both from the servers' own `cpu_s`. tier.json holds every figure.
#include <algorithm>
#include <cstdio>
#include <map>
#include <memory>
#include <optional>

#include "bench/bench.h"
#include "bench/bench_model.h"
#include "bench/failover_flight.h"
#include "bench/loopback_daemon.h"
#include "bench/nginx_child.h"
#include "bench/report.h"
#include "bench/serve_child.h"
#include "bench/tier_flight.h"
#include "common/error.h"

namespace pms::bench {
using app::PathKind;
using nlohmann::json;
namespace {

const char* const kDefaultModel = "dragon";
constexpr float kTolerance = 1;
constexpr uint32_t kPaths = 20, kViewersPerPath = 5, kQuickPaths = 4, kQuickViewersPerPath = 3;
constexpr uint32_t kFrames = 30, kLongFrames = 120;
// The viewers of a path start this far apart (the first of every path at once): a later viewer finds
// what the earlier ones asked for in the cache, or waits on its lock.
constexpr std::chrono::milliseconds kStagger{1000};
// Issue 45's targets for the tier.
constexpr double kTargetCpuRatio = 0.3, kTargetLaterHitRate = 0.9;

// Path j: frames of an orbit, a scan or a zoom (j % 3) from a phase of its own.
std::vector<std::vector<Camera>> mixed_paths(const BenchModel& m, uint32_t paths) {
  const std::vector<Camera> kinds[] = {path_of(m, PathKind::orbit, kLongFrames), path_of(m, PathKind::scan, kLongFrames),
                                       path_of(m, PathKind::zoom, kLongFrames)};
  std::vector<std::vector<Camera>> out;
  for (uint32_t j = 0; j < paths; ++j) {
    const std::vector<Camera>& kind = kinds[j % 3];
    const size_t phase = size_t(j / 3) * 13 % (kLongFrames - kFrames);
    out.emplace_back(kind.begin() + std::ptrdiff_t(phase), kind.begin() + std::ptrdiff_t(phase + kFrames));
  }
  return out;
}

// An origin's counters: http's beside the process's CPU.
struct OriginCounters {
  double cpu_s = 0;
  uint64_t requests = 0, split_requests = 0, bytes_out = 0, not_modified = 0;
};

OriginCounters origin_counters(ServeChild& origin) {
  const ServeStats s = origin.stats();
  const json& h = s.line.at("http");
  return {s.cpu_s, h.at("requests").get<uint64_t>(), h.at("split_requests").get<uint64_t>(),
          h.at("bytes_out").get<uint64_t>(), h.at("not_modified").get<uint64_t>()};
}

OriginCounters operator-(const OriginCounters& a, const OriginCounters& b) {
  return {a.cpu_s - b.cpu_s, a.requests - b.requests, a.split_requests - b.split_requests, a.bytes_out - b.bytes_out,
          a.not_modified - b.not_modified};
}

OriginCounters& operator+=(OriginCounters& a, const OriginCounters& b) {
  a.cpu_s += b.cpu_s;
  a.requests += b.requests;
  a.split_requests += b.split_requests;
  a.bytes_out += b.bytes_out;
  a.not_modified += b.not_modified;
  return a;
}

// The access log's requests and body bytes by cache status ("HIT", "MISS", "-" for none, ...).
struct CacheStatusTotals {
  uint64_t requests = 0, body_bytes = 0;
};

struct TierFigures {
  uint32_t viewers = 0, failed = 0;
  std::vector<std::string> failures;  // the first few
  uint64_t split_gets = 0, hits = 0, later_split_gets = 0, later_hits = 0;
  uint64_t splits = 0, bytes_down = 0, payload_down = 0;
  OriginCounters origins;                  // both origins over the flight (the killed one until its kill)
  std::map<std::string, CacheStatusTotals> cache;  // nginx's access log
  uint64_t failed_over = 0;                        // requests nginx sent to a second origin
  uint64_t server_errors = 0;                      // 5xx answers nginx gave viewers
  double killed_at_s = 0;                  // the flight's second the origin was killed at
};

struct SenderFigures {
  uint32_t viewers = 0, failed = 0;
  uint64_t splits_sent = 0, splits_received = 0;
  double cpu_s = 0;
};

struct TierRun {
  std::optional<TierFigures> tier;
  std::optional<SenderFigures> sender;
  std::string error;
};

std::vector<std::string> origin_args(const BenchModel& m) {
  return {m.pms.string(), "--http-port", "0", "--trusted-proxy", "127.0.0.1"};
}

TierPlan tier_plan(const std::string& model, const NginxChild& nginx,
                   const std::vector<std::vector<Camera>>& paths, uint32_t per_path) {
  TierPlan plan;
  plan.server = client::parse_http_url(nginx.url());
  plan.model = model;
  plan.tolerance = kTolerance;
  for (uint32_t rank = 0; rank < per_path; ++rank)
    for (size_t j = 0; j < paths.size(); ++j) {
      const size_t i = plan.viewers.size();
      // 127.0.0.0/8 is loopback: each viewer its own address, as the origins' accounting should see it.
      const std::string address = "127.0." + std::to_string(1 + i / 250) + "." + std::to_string(2 + i % 250);
      plan.viewers.push_back({paths[j], client::FetchPolicy::blocks, address, rank * kStagger});
    }
  // The first viewer of the middle rank, halfway: the first viewers of every path near their end, the
  // last ones starting.
  plan.event_viewer = paths.size() * (per_path / 2);
  plan.event_frame = kFrames / 2;
  return plan;
}

TierFigures tier_figures(const std::vector<TierViewer>& viewers, size_t paths) {
  TierFigures f;
  f.viewers = uint32_t(viewers.size());
  for (size_t i = 0; i < viewers.size(); ++i) {
    const TierViewer& v = viewers[i];
    if (!v.error.empty()) {
      ++f.failed;
      if (f.failures.size() < 5) f.failures.push_back("viewer " + std::to_string(i) + ": " + v.error);
      continue;
    }
    f.split_gets += v.totals.split_requests;
    f.hits += v.totals.cache_hits;
    if (i >= paths) {  // tier_plan() puts every path's first viewer first
      f.later_split_gets += v.totals.split_requests;
      f.later_hits += v.totals.cache_hits;
    }
    f.splits += v.splits;
    f.bytes_down += v.counters.bytes_down;
    f.payload_down += v.counters.payload_down;
  }
  return f;
}

TierFigures fly_through_tier(const BenchContext& context, const BenchModel& m, const std::string& nginx_program,
                             const std::vector<std::vector<Camera>>& paths, uint32_t per_path) {
  std::vector<std::unique_ptr<ServeChild>> origins;
  std::vector<uint16_t> ports;
  for (int i = 0; i < 2; ++i) {
    origins.push_back(std::make_unique<ServeChild>(context.pmstream_exe, origin_args(m)));
    ports.push_back(origins.back()->listening().at("http_port").get<uint16_t>());
  }
  NginxChild nginx(nginx_program, PMSTREAM_NGINX_CONFIG, context.temp_dir / "nginx-tier", ports);
  const OriginCounters before[] = {origin_counters(*origins[0]), origin_counters(*origins[1])};
  OriginCounters killed;
  const auto t0 = std::chrono::steady_clock::now();
  double killed_at_s = 0;
  TierPlan plan = tier_plan(m.name, nginx, paths, per_path);
  plan.event = [&] {
    killed = origin_counters(*origins[0]) - before[0];  // its last report: what it did until the kill
    origins[0].reset();                                 // SIGKILL
    killed_at_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::fprintf(stderr, "bench: tier, origin1 killed at %.1f s\n", killed_at_s);
  };
  std::fprintf(stderr, "bench: tier, %zu viewers through nginx over two origins\n", plan.viewers.size());
  const std::vector<TierViewer> viewers = fly_tier(plan);
  TierFigures f = tier_figures(viewers, paths.size());
  f.origins = killed;
  f.origins += origin_counters(*origins[1]) - before[1];
  f.killed_at_s = killed_at_s;
  for (const AccessLogLine& line : read_access_log(nginx.access_log())) {
    CacheStatusTotals& t = f.cache[line.cache];
    ++t.requests;
    t.body_bytes += line.body_bytes;
    f.failed_over += line.upstreams.find(',') != std::string::npos;
    f.server_errors += line.status >= 500;
  }
  return f;
}

SenderFigures fly_sender_driven(const BenchContext& context, const BenchModel& m,
                                const std::vector<std::vector<Camera>>& paths, uint32_t per_path) {
  ServeChild server(context.pmstream_exe, {m.pms.string(), "--max-sessions", std::to_string(paths.size() * per_path + 16)});
  const ServeStats before = server.stats();
  FailoverPlan plan;
  plan.model = m.name;
  plan.tolerance = kTolerance;
  for (uint32_t rank = 0; rank < per_path; ++rank)
    for (const std::vector<Camera>& path : paths) plan.viewers.push_back({path, server.port(), ""});
  std::fprintf(stderr, "bench: tier, the same %zu viewers sender-driven against one server\n", plan.viewers.size());
  const std::vector<FailoverViewer> viewers = fly_failover(plan);
  const ServeStats after = server.stop();  // a session's splits count once it has closed
  SenderFigures f;
  f.viewers = uint32_t(viewers.size());
  for (const FailoverViewer& v : viewers) {
    f.failed += !v.error.empty();
    f.splits_received += v.splits_received;
  }
  f.splits_sent = after.splits_sent - before.splits_sent;
  f.cpu_s = after.cpu_s - before.cpu_s;
  return f;
}

double share(uint64_t part, uint64_t whole) { return whole ? double(part) / double(whole) : 0; }
double us_per(double seconds, uint64_t count) { return count ? 1e6 * seconds / double(count) : 0; }

uint64_t cache_bytes(const TierFigures& f, bool from_cache) {
  uint64_t bytes = 0;
  for (const auto& [status, t] : f.cache) {
    const bool cached = status == "HIT" || status == "STALE" || status == "UPDATING" || status == "REVALIDATED";
    if (cached == from_cache) bytes += t.body_bytes;
  }
  return bytes;
}

std::string percent(double value) { return fixed(100 * value, 1) + " %"; }

Table tier_table(const TierRun& run) {
  const TierFigures& t = *run.tier;
  const SenderFigures& s = *run.sender;
  Table table({{"flight", false},
               {"viewers", true},
               {"failed", true},
               {"origin requests", true},
               {"split GETs", true},
               {"hit rate", true},
               {"from 2nd viewer", true},
               {"bytes from cache", true},
               {"bytes from origins", true},
               {"splits", true},
               {"server CPU s", true},
               {"µs / split", true}});
  table.add_row({"receiver-driven, nginx + 2 origins", thousands(t.viewers), thousands(t.failed),
                 thousands(t.origins.requests), thousands(t.split_gets), percent(share(t.hits, t.split_gets)),
                 percent(share(t.later_hits, t.later_split_gets)), thousands(cache_bytes(t, true)),
                 thousands(t.origins.bytes_out), thousands(t.splits), fixed(t.origins.cpu_s, 2),
                 fixed(us_per(t.origins.cpu_s, t.splits), 2)});
  table.add_row({"sender-driven, 1 server", thousands(s.viewers), thousands(s.failed), "", "", "", "", "", "",
                 thousands(s.splits_sent), fixed(s.cpu_s, 2), fixed(us_per(s.cpu_s, s.splits_sent), 2)});
  return table;
}

std::string met(bool ok) { return ok ? "met" : "**missed**"; }

std::string summary(const TierRun& run, const std::string& model, uint32_t paths, uint32_t per_path) {
  const TierFigures& t = *run.tier;
  const SenderFigures& s = *run.sender;
  std::string text = "- " + std::to_string(paths * per_path) + " receiver-driven viewers (lock-step, τ = " +
                     fixed(kTolerance, 0) + " px, `--fetch blocks`) on " + model + ", " + std::to_string(paths) +
                     " paths of " + std::to_string(kFrames) + " frames (orbits, scans and zooms, each from a phase of "
                     "its own), " + std::to_string(per_path) + " viewers a path starting " +
                     std::to_string(kStagger.count()) + " ms apart, each from a loopback address of its own, "
                     "through nginx (deploy/nginx/pmstream-cache.conf) over two origins trusting its "
                     "X-Forwarded-For; origin1 killed (SIGKILL) when the first viewer of rank " + std::to_string(per_path / 2 + 1) +
                     " reached frame " + std::to_string(kFrames / 2) + ", " + fixed(t.killed_at_s, 1) + " s into the flight.\n";
  text += "- origins: " + thousands(t.origins.requests) + " requests (" + thousands(t.origins.split_requests) +
          " for splits, " + thousands(t.origins.not_modified) + " answered 304), " + thousands(t.origins.bytes_out) +
          " bytes out; the viewers got " + thousands(t.bytes_down) + " bytes (" + thousands(t.payload_down) +
          " of bodies), of which nginx served " + thousands(cache_bytes(t, true)) + " body bytes from its cache and " +
          thousands(cache_bytes(t, false)) + " from the origins. Access log by cache status:";
  for (const auto& [status, c] : t.cache)
    text += " " + status + " " + thousands(c.requests) + " (" + thousands(c.body_bytes) + " B);";
  text.back() = '.';
  text += " nginx sent " + thousands(t.failed_over) + " requests on to the other origin after one failed, and "
          "answered " + thousands(t.server_errors) + " with a 5xx.\n";
  const double tier_us = us_per(t.origins.cpu_s, t.splits), sender_us = us_per(s.cpu_s, s.splits_sent);
  const double ratio = sender_us > 0 ? tier_us / sender_us : 0;
  const double later = share(t.later_hits, t.later_split_gets);
  text += "- origin CPU per split delivered to viewers: " + fixed(tier_us, 2) + " µs (both origins' `cpu_s` over the "
          "flight, the killed one's until its last report just before the kill, over the " + thousands(t.splits) +
          " splits the viewers received); the sender-driven server's per split sent on the same paths: " +
          fixed(sender_us, 2) + " µs (" + thousands(s.splits_sent) + " splits, " + thousands(s.splits_received) +
          " received); ratio " + fixed(ratio, 3) + ". The receiver-driven viewers receive more splits on the same "
          "paths (a block brings its band's descendants); per viewer, the origins spent " +
          fixed(t.origins.cpu_s / std::max(1u, t.viewers), 4) + " s of CPU against the sender-driven server's " +
          fixed(s.cpu_s / std::max(1u, s.viewers), 4) + " s (ratio " +
          fixed(s.cpu_s > 0 ? t.origins.cpu_s / s.cpu_s : 0, 3) + ").\n";
  text += "- targets (issue 45): 0 viewers failed: " + met(t.failed == 0) + "; origin CPU per split delivered ≤ " +
          fixed(kTargetCpuRatio, 1) + "× the sender-driven server's: " + met(ratio > 0 && ratio <= kTargetCpuRatio) +
          "; hit rate ≥ " + percent(kTargetLaterHitRate) + " from the second viewer of a path on: " +
          met(later >= kTargetLaterHitRate) + ".\n";
  for (const std::string& failure : t.failures) text += "- failed: " + failure + "\n";
  return text;
}

json figures_json(const TierFigures& t) {
  json cache = json::object();
  for (const auto& [status, c] : t.cache) cache[status] = {{"requests", c.requests}, {"body_bytes", c.body_bytes}};
  return {{"viewers", t.viewers},
          {"failed", t.failed},
          {"failures", t.failures},
          {"split_gets", t.split_gets},
          {"cache_hits", t.hits},
          {"later_split_gets", t.later_split_gets},
          {"later_cache_hits", t.later_hits},
          {"splits_received", t.splits},
          {"bytes_down", t.bytes_down},
          {"payload_down", t.payload_down},
          {"origin_requests", t.origins.requests},
          {"origin_split_requests", t.origins.split_requests},
          {"origin_not_modified", t.origins.not_modified},
          {"origin_bytes_out", t.origins.bytes_out},
          {"origin_cpu_s", t.origins.cpu_s},
          {"killed_at_s", t.killed_at_s},
          {"failed_over_requests", t.failed_over},
          {"server_error_answers", t.server_errors},
          {"access_log", cache}};
}

}  // namespace

void run_tier_group(BenchContext& context) {
  std::string section = "## tier: receiver-driven viewers behind an nginx cache over two origins, one killed\n\n";
  if (skipped_without_models(context, section)) return;
  const std::string nginx = find_daemon("nginx");
  if (nginx.empty()) {
    context.report += section + "Not measured: nginx is not installed (scripts/setup.sh installs Debian's).\n\n";
    return;
  }
  const bool quick = context.options.quick;
  const uint32_t paths = quick ? kQuickPaths : kPaths, per_path = quick ? kQuickViewersPerPath : kViewersPerPath;
  const std::string name =
      !context.options.models.empty() ? context.options.models.back() : quick ? "bunny" : kDefaultModel;
  const BenchModel m = prepare_model(context, name);
  const std::vector<std::vector<Camera>> camera_paths = mixed_paths(m, paths);
  TierRun run;
  try {
    run.tier = fly_through_tier(context, m, nginx, camera_paths, per_path);
    run.sender = fly_sender_driven(context, m, camera_paths, per_path);
  } catch (const Error& e) {
    run.error = e.what();
  }
  if (!run.error.empty()) {
    context.failures.push_back("tier: " + run.error);
    context.report += section + "**Not measured**: " + run.error + "\n\n";
    return;
  }
  const std::string text = tier_table(run).markdown() + "\n" + summary(run, name, paths, per_path) + "\n";
  std::printf("\ntier: %u viewers through nginx on %s\n%s", paths * per_path, name.c_str(), text.c_str());
  std::fflush(stdout);
  const json out = {{"command", context.options.command_line},
                    {"machine", machine_json()},
                    {"model", name},
                    {"paths", paths},
                    {"viewers_per_path", per_path},
                    {"frames", kFrames},
                    {"tolerance_px", kTolerance},
                    {"stagger_ms", kStagger.count()},
                    {"tier", figures_json(*run.tier)},
                    {"sender",
                     {{"viewers", run.sender->viewers},
                      {"failed", run.sender->failed},
                      {"splits_sent", run.sender->splits_sent},
                      {"splits_received", run.sender->splits_received},
                      {"cpu_s", run.sender->cpu_s}}},
                    {"target", {{"cpu_ratio_max", kTargetCpuRatio}, {"later_hit_rate_min", kTargetLaterHitRate}}}};
  write_text_file(context.options.out_dir / "tier.json", out.dump(2) + "\n");
  context.report += section + text;
}

}  // namespace pms::bench
