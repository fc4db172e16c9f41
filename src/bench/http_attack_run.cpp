// The quiet flight, the attacked flight and the watch around them (http_attack_run.h). As in the TCP attack
// tests, a pair whose p99 ratio misses the bound is flown twice more, quiet then attacked, and the median
// of the pairs' ratios is what counts: the virtual machines these runs see stall a process a few times a
// minute, and one stall in either flight moves a p99 of a few hundred answers far more than an attack does.
#include "bench/http_attack_run.h"

#include <algorithm>
#include <atomic>
#include <memory>
#include <set>
#include <thread>

#include "apps/percentile.h"
#include "bench/serve_child.h"
#include "bench/server_watch.h"
#include "client/http_connection.h"
#include "client/receiver_client.h"
#include "protocol/url_segment.h"

namespace pms::bench {
namespace {

using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

// How long the flight waits for every attacker to be under way before it starts anyway.
constexpr milliseconds kUnderWayWait(5000);

constexpr double kIdleShare = 0.10;
constexpr milliseconds kIdleWithin(3000);

AttackFlight fly(const AttackSetup& setup, uint16_t port) {
  AttackFlight flight;
  const Clock::time_point start = Clock::now();
  try {
    client::ReceiverOptions options;
    options.tolerance = setup.tolerance;
    client::ReceiverClient* self = nullptr;
    options.on_attached = [&] { flight.latency_ms.push_back(self->counters().last_answer_ms); };
    client::ReceiverClient client(client::HttpUrl{"127.0.0.1", port, ""}, options);
    self = &client;
    client.open(setup.model_name);
    for (const Camera& camera : setup.path) client.frame(camera);
    flight.mesh = faces_by_id(client.session().mesh());
  } catch (const std::exception& e) {
    flight.error = e.what();
  }
  flight.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  return flight;
}

// The http object's counters as they grew from `before`; its gauges as they are `after`.
nlohmann::json grown(const nlohmann::json& before, const nlohmann::json& after) {
  static const std::set<std::string> gauges = {"connections_active", "addresses_tracked", "longest_turn_us",
                                               "socket_buffer_bound_bytes"};
  nlohmann::json out = nlohmann::json::object();
  for (const auto& [name, value] : after.items()) {
    if (!value.is_number_unsigned()) continue;
    if (gauges.contains(name)) {
      out[name] = value;
      continue;
    }
    const uint64_t was = before.contains(name) ? before.at(name).get<uint64_t>() : 0;
    out[name] = value.get<uint64_t>() >= was ? value.get<uint64_t>() - was : 0;
  }
  return out;
}

class GroupRun {
 public:
  GroupRun(const AttackSetup& setup, AttackTarget target, const AttackGroup& group)
      : setup_(setup), target_(std::move(target)), group_(group) {
    outcome_.group = group.name;
    outcome_.classes = group.classes;
    outcome_.tallies.resize(group.classes.size());
  }

  AttackOutcome run() {
    try {
      ServeChild server(setup_.pmstream_exe, server_args());
      const uint16_t port = server.listening().at("http_port").get<uint16_t>();
      target_.port = port;
      aim_unread_pipeline(port);
      const pid_t pid = server.pid();
      outcome_.quiet = fly(setup_, port);
      outcome_.quiet_rss = process_rss_bytes(pid);
      const nlohmann::json before = server.stats().line.at("http");
      outcome_.memory_bound = outcome_.quiet_rss + before.at("socket_buffer_bound_bytes").get<uint64_t>();
      {
        MemoryWatch watch(pid, port);
        fly_pairs(pid, port);
        outcome_.peak_rss = watch.peak_rss();
        outcome_.peak_sockets = watch.peak_sockets();
        outcome_.peak_total = watch.peak_total();
      }
      outcome_.http = grown(before, server.stats().line.at("http"));
      const Clock::time_point stop_start = Clock::now();
      server.stop(10);
      outcome_.sigterm_s = std::chrono::duration<double>(Clock::now() - stop_start).count();
    } catch (const std::exception& e) {
      outcome_.error = e.what();
    }
    return std::move(outcome_);
  }

 private:
  std::vector<std::string> server_args() const {
    auto ms = [](milliseconds m) { return std::to_string(m.count()); };
    return {setup_.model_pms,
            "--http-port",
            "0",
            "--threads",
            "2",
            "--preload",
            "receiver",
            "--http-request-timeout-ms",
            ms(setup_.request_timeout),
            "--http-write-timeout-ms",
            ms(setup_.write_timeout),
            "--http-idle-timeout-ms",
            ms(setup_.idle_timeout)};
  }

  // BASEs, as many as fit well within the server's send buffer (Linux holds twice the 128 KiB asked) and
  // well over the unread peer's 4 KiB window; the catalogue when one BASE is too large for that.
  void aim_unread_pipeline(uint16_t port) {
    constexpr size_t kFits = 160u << 10;
    client::HttpConnection http(client::HttpUrl{"127.0.0.1", port, ""});
    const size_t base = http.get(target_.model + "/base").body.size() + 200;  // and its head
    target_.unread = base <= kFits ? target_.model + "/base" : "/models";
    target_.unread_count = base <= kFits ? uint32_t(std::clamp<size_t>(kFits / base, 1, 16)) : 16;
  }

  double ratio() const {
    const double quiet = p99(outcome_.quiet.latency_ms);
    return quiet > 0 ? p99(outcome_.attacked.latency_ms) / quiet : 0;
  }

  // The attacked flight, then pairs again while the median ratio misses the bound (at most three pairs).
  void fly_pairs(pid_t pid, uint16_t port) {
    std::vector<double> ratios;
    outcome_.same_mesh = true;
    for (int pair = 0; pair < 3; ++pair) {
      if (pair > 0) outcome_.quiet = fly(setup_, port);
      attack_during_flight(pid, port);
      outcome_.same_mesh = outcome_.same_mesh && outcome_.attacked.error.empty() && outcome_.quiet.error.empty() &&
                           outcome_.attacked.mesh == outcome_.quiet.mesh;
      ratios.push_back(ratio());
      outcome_.idle_after_s = seconds_to_idle(pid, kIdleShare, kIdleWithin, outcome_.idle_use);
      std::vector<double> sorted = ratios;
      std::sort(sorted.begin(), sorted.end());
      outcome_.median_ratio = sorted[sorted.size() / 2];
      outcome_.pairs = ratios.size();
      if (!setup_.compare_p99 || outcome_.median_ratio <= kMaxP99Ratio) return;
    }
  }

  void attack_during_flight(pid_t pid, uint16_t port) {
    std::atomic<bool> stop{false};
    std::vector<std::thread> attackers;
    const Clock::time_point start = Clock::now();
    for (size_t c = 0; c < group_.classes.size(); ++c)
      for (int i = 0; i < setup_.attackers_per_class; ++i)
        attackers.emplace_back(run_attacker, group_.classes[c], std::cref(target_), i, std::cref(stop),
                               std::ref(outcome_.tallies[c]));
    wait_until_under_way(start);
    const double cpu_before = process_cpu_seconds(pid);
    outcome_.attacked = fly(setup_, port);
    for (const Clock::time_point until = start + setup_.min_attack; Clock::now() < until;)
      std::this_thread::sleep_for(milliseconds(20));  // the attack's length, not a wait for anything
    stop = true;
    for (std::thread& t : attackers) t.join();
    outcome_.attack_cpu_s = process_cpu_seconds(pid) - cpu_before;
  }

  // Every attacker has begun a round (the flood its connections), or kUnderWayWait has passed.
  void wait_until_under_way(Clock::time_point start) const {
    const auto begun = [&] {
      for (const AttackTally& tally : outcome_.tallies)
        if (tally.rounds < uint64_t(setup_.attackers_per_class)) return false;
      return true;
    };
    while (!begun() && Clock::now() < start + kUnderWayWait) std::this_thread::sleep_for(milliseconds(5));
  }

  const AttackSetup& setup_;
  AttackTarget target_;
  const AttackGroup& group_;
  AttackOutcome outcome_;
};

}  // namespace

double p99(const std::vector<double>& samples) { return samples.empty() ? 0 : app::percentile(samples, 0.99); }

AttackOutcome run_attack_group(const AttackSetup& setup, const AttackGroup& group) {
  AttackTarget target;
  target.model = setup.model_path;
  target.expensive = setup.expensive;
  target.request_timeout = setup.request_timeout;
  target.write_timeout = setup.write_timeout;
  target.idle_timeout = setup.idle_timeout;
  target.slack = setup.slack;
  return GroupRun(setup, std::move(target), group).run();
}

}  // namespace pms::bench
