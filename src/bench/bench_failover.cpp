// The soak group's failover figure (issue 45, requirement 3): sender-driven viewers (client::StreamingClient,
// lock-step, half of them over the WebSocket) fly bunny through Debian's HAProxy with the shipped
// deploy/haproxy/pmstream.cfg in front of two `pmstream serve` origins, once undisturbed and once with one
// origin killed (SIGKILL) when the first viewer is halfway, the others flying on, so answers are cut in the
// middle. The report compares the two flights viewer by viewer: failures, resumes, splits received and
// arrived twice, bytes down beyond the undisturbed flight and how much of it is re-sent bases, and the
// resume latency (the loss noticed -> that frame's view satisfied on the other origin). failover.json
// holds every figure.
#include <cstdio>
#include <memory>
#include <optional>

#include "apps/percentile.h"
#include "bench/bench.h"
#include "bench/bench_model.h"
#include "bench/failover_flight.h"
#include "bench/haproxy_child.h"
#include "bench/loopback_daemon.h"
#include "bench/report.h"
#include "bench/serve_child.h"
#include "common/error.h"

namespace pms::bench {
using app::percentile;
using nlohmann::json;
namespace {

const char* const kDefaultModel = "bunny";
constexpr float kTolerance = 1;
constexpr uint32_t kViewers = 50, kQuickViewers = 10;
constexpr uint32_t kFrames = 60;

// What one flight of every viewer came to.
struct FlightFigures {
  uint32_t viewers = 0, failed = 0, resumed_viewers = 0, resumes = 0, attempts = 0;
  uint32_t lost_mid_frame = 0;  // resumes after part of the frame's splits had arrived
  uint64_t splits_received = 0, arrived_twice = 0, bytes_down = 0;
  int64_t extra_bytes = 0;  // bytes down beyond the undisturbed flight's, viewer by viewer
  uint64_t resent_base_bytes = 0;
  std::vector<double> resume_ms;
  std::vector<std::string> failures;  // the first few
};

FlightFigures figures_of(const std::vector<FailoverViewer>& flight, const std::vector<FailoverViewer>& calm) {
  FlightFigures f;
  f.viewers = uint32_t(flight.size());
  for (size_t i = 0; i < flight.size(); ++i) {
    const FailoverViewer& v = flight[i];
    if (!v.error.empty()) {
      ++f.failed;
      if (f.failures.size() < 5) f.failures.push_back("viewer " + std::to_string(i) + ": " + v.error);
      continue;
    }
    f.resumed_viewers += !v.resume_ms.empty();
    f.resumes += uint32_t(v.resume_ms.size());
    f.attempts += v.attempts;
    f.lost_mid_frame += v.lost_mid_frame;
    f.splits_received += v.splits_received;
    f.arrived_twice += v.splits_received - v.splits_held;
    f.bytes_down += v.total.bytes_down;
    f.resume_ms.insert(f.resume_ms.end(), v.resume_ms.begin(), v.resume_ms.end());
    if (calm[i].error.empty()) {
      f.extra_bytes += int64_t(v.total.bytes_down) - int64_t(calm[i].total.bytes_down);
      f.resent_base_bytes += v.resume_ms.size() * calm[i].opened.bytes_down;
    }
  }
  return f;
}

// Every viewer on the same orbit from a phase of its own; every other one over the WebSocket.
FailoverPlan plan_of(const BenchModel& m, const HaproxyChild& proxy, uint32_t viewers) {
  const std::vector<Camera> orbit = path_of(m, app::PathKind::orbit, kFrames);
  FailoverPlan plan;
  plan.model = m.name;
  plan.tolerance = kTolerance;
  for (uint32_t i = 0; i < viewers; ++i) {
    std::vector<Camera> path;
    for (size_t k = 0; k < orbit.size(); ++k) path.push_back(orbit[(k + size_t(i) * 7) % orbit.size()]);
    const bool ws = i % 2 == 1;
    plan.viewers.push_back({path, ws ? proxy.http_port() : proxy.session_port(), ws ? "/ws" : ""});
  }
  return plan;
}

struct FailoverRun {
  std::optional<FlightFigures> calm, killed;
  uint64_t killed_sessions = 0;  // on the killed origin just before (a health check's may be among them)
  std::string error;             // the run could not be made
};

FailoverRun run_failover(const BenchContext& context, const BenchModel& m, const std::string& haproxy,
                         uint32_t viewers) {
  FailoverRun run;
  try {
    std::vector<std::unique_ptr<ServeChild>> origins;
    std::vector<HaproxyOrigin> ports;
    for (int i = 0; i < 2; ++i) {
      origins.push_back(std::make_unique<ServeChild>(
          context.pmstream_exe,
          std::vector<std::string>{m.pms.string(), "--http-port", "0", "--trusted-proxy", "127.0.0.1"}));
      ports.push_back({origins.back()->port(), origins.back()->listening()["http_port"].get<uint16_t>()});
    }
    HaproxyChild proxy(haproxy, PMSTREAM_HAPROXY_CONFIG, ports);
    for (const char* origin : {"origin1", "origin2"})
      if (!proxy.await_state(origin, "UP", std::chrono::seconds(20)))
        fail("haproxy", std::string(origin) + " is not UP");
    std::fprintf(stderr, "bench: failover, %u viewers through haproxy, undisturbed\n", viewers);
    const std::vector<FailoverViewer> calm = fly_failover(plan_of(m, proxy, viewers));
    FailoverPlan disturbed = plan_of(m, proxy, viewers);
    disturbed.event_frame = kFrames / 2;
    disturbed.event = [&] {
      const json line = origins[0]->stats().line;
      run.killed_sessions = line["sessions_active"].get<uint64_t>() + line["ws"]["sessions_active"].get<uint64_t>();
      origins[0].reset();  // SIGKILL
    };
    std::fprintf(stderr, "bench: failover, %u viewers through haproxy, one origin killed halfway\n", viewers);
    const std::vector<FailoverViewer> killed = fly_failover(disturbed);
    run.calm = figures_of(calm, calm);
    run.killed = figures_of(killed, calm);
  } catch (const Error& e) {
    run.error = e.what();
  }
  return run;
}

std::string signed_thousands(int64_t value) {
  std::string text = thousands(uint64_t(value < 0 ? -value : value));
  if (value < 0) text.insert(text.begin(), '-');
  return text;
}

std::string ms(const std::vector<double>& values, double p) {
  return values.empty() ? "–" : fixed(percentile(values, p), 1);
}

Table flight_table(const FailoverRun& run) {
  Table table({{"flight", false},
               {"viewers", true},
               {"failed", true},
               {"resumed", true},
               {"attempts", true},
               {"mid-frame", true},
               {"splits received", true},
               {"arrived twice", true},
               {"bytes down", true},
               {"extra bytes", true},
               {"re-sent bases", true},
               {"resume p50 ms", true},
               {"p90", true},
               {"p99", true},
               {"max", true}});
  for (const auto& [name, f] : {std::pair{"undisturbed", &*run.calm}, std::pair{"origin killed", &*run.killed}})
    table.add_row({name, thousands(f->viewers), thousands(f->failed), thousands(f->resumed_viewers),
                   thousands(f->attempts), thousands(f->lost_mid_frame), thousands(f->splits_received),
                   thousands(f->arrived_twice), thousands(f->bytes_down), signed_thousands(f->extra_bytes),
                   thousands(f->resent_base_bytes), ms(f->resume_ms, 0.5), ms(f->resume_ms, 0.9),
                   ms(f->resume_ms, 0.99), ms(f->resume_ms, 1)});
  return table;
}

// failover.json's fields are the figures' names (written by hand: the macro's from_json would go unused).
void to_json(nlohmann::json& out, const FlightFigures& f) {
  out = {{"viewers", f.viewers},
         {"failed", f.failed},
         {"resumed_viewers", f.resumed_viewers},
         {"resumes", f.resumes},
         {"attempts", f.attempts},
         {"lost_mid_frame", f.lost_mid_frame},
         {"splits_received", f.splits_received},
         {"arrived_twice", f.arrived_twice},
         {"bytes_down", f.bytes_down},
         {"extra_bytes", f.extra_bytes},
         {"resent_base_bytes", f.resent_base_bytes},
         {"resume_ms", f.resume_ms},
         {"failures", f.failures}};
}

std::string summary(const FailoverRun& run, const std::string& model, uint32_t viewers) {
  const FlightFigures &calm = *run.calm, &killed = *run.killed;
  std::string text = "- " + std::to_string(viewers) + " sender-driven viewers (lock-step, τ = " + fixed(kTolerance, 0) +
                     " px, every other one over the WebSocket) on " + model + ", each a " + std::to_string(kFrames) +
                     "-frame orbit from its own phase, through HAProxy (deploy/haproxy/pmstream.cfg) in front of two "
                     "origins; the second flight kills origin1 (SIGKILL) when its first viewer reaches frame " +
                     std::to_string(kFrames / 2) + ", the others flying on.\n";
  text +=
      "- " + std::to_string(run.killed_sessions) + " sessions were on the killed origin (one may be a health check); " +
      std::to_string(killed.resumed_viewers) + " viewers resumed, with " + std::to_string(killed.attempts) +
      " reconnect attempts for " + std::to_string(killed.resumes) + " resumes; " +
      std::to_string(killed.lost_mid_frame) +
      " of them mid-frame, with some of the frame's splits in (an answer the kill cut, or the frame's next request).\n";
  const bool same_splits = killed.splits_received == calm.splits_received;
  text += "- splits received: " + thousands(killed.splits_received) + " against " + thousands(calm.splits_received) +
          " undisturbed (" + (same_splits ? "the same" : "**not the same**") +
          "); arrived twice: " + thousands(killed.arrived_twice) +
          ". Extra bytes down: " + signed_thousands(killed.extra_bytes) + ", of which " +
          thousands(killed.resent_base_bytes) + " are the re-sent bases (HELLO_OK, BASE, CODEC per resume); " +
          signed_thousands(killed.extra_bytes - int64_t(killed.resent_base_bytes)) +
          " more is the framing of answers the kill cut, which the other origin finished in batches of its own.\n";
  const bool met = killed.failed == 0 && killed.arrived_twice == 0 && same_splits;
  text += std::string("- target (issue 45): 0 viewers failed, 0 splits sent twice: ") + (met ? "met" : "**missed**") +
          ".\n";
  for (const std::string& failure : killed.failures) text += "- failed: " + failure + "\n";
  return text;
}

}  // namespace

void run_failover_figure(BenchContext& context) {
  std::string section = "## failover: sender-driven viewers behind HAProxy, one origin killed\n\n";
  if (skipped_without_models(context, section)) return;
  const std::string haproxy = find_daemon("haproxy");
  if (haproxy.empty()) {
    context.report += section + "Not measured: haproxy is not installed (scripts/setup.sh installs Debian's).\n\n";
    return;
  }
  const uint32_t viewers = context.options.quick ? kQuickViewers : kViewers;
  const std::string name = kDefaultModel;
  const BenchModel m = prepare_model(context, name);
  const FailoverRun run = run_failover(context, m, haproxy, viewers);
  if (!run.error.empty()) {
    context.failures.push_back("failover: " + run.error);
    context.report += section + "**Not measured**: " + run.error + "\n\n";
    return;
  }
  const std::string text = flight_table(run).markdown() + "\n" + summary(run, name, viewers) + "\n";
  std::printf("\nfailover: %u viewers through haproxy on %s\n%s", viewers, name.c_str(), text.c_str());
  std::fflush(stdout);
  const json out = {{"command", context.options.command_line},
                    {"machine", machine_json()},
                    {"model", name},
                    {"viewers", viewers},
                    {"frames", kFrames},
                    {"tolerance_px", kTolerance},
                    {"killed_sessions", run.killed_sessions},
                    {"undisturbed", *run.calm},
                    {"origin_killed", *run.killed}};
  write_text_file(context.options.out_dir / "failover.json", out.dump(2) + "\n");
  context.report += section + text;
}

}  // namespace pms::bench
