#include "bench/soak_client.h"

#include <algorithm>
#include <random>
#include <thread>

#include "bench/report.h"
#include "client/load_client.h"
#include "common/error.h"

namespace pms::bench {
namespace {

using Clock = std::chrono::steady_clock;

// A dropped connection every 30–90 s (uniform): at 100 clients over a minute about as many reconnects as
// clients, so resumes and new sessions go on all the time rather than once.
constexpr uint64_t kReconnectMinMs = 30'000, kReconnectMaxMs = 90'000;
constexpr std::chrono::milliseconds kAnswerTimeout{30'000};
constexpr size_t kFailuresKept = 5;

double seconds_between(Clock::time_point from, Clock::time_point to) {
  return std::chrono::duration<double>(to - from).count();
}

}  // namespace

const Camera& SoakPath::at(uint64_t frame) const {
  const uint64_t n = cameras->size();
  const uint64_t period = ping_pong && n > 1 ? 2 * (n - 1) : n;
  const uint64_t step = reversed ? period - 1 : 1;  // -1 modulo the period
  const uint64_t k = (phase + frame % period * step) % period;
  return (*cameras)[k < n ? k : period - k];
}

SoakPath SoakPath::of_client(uint32_t i, const std::vector<Camera>& orbit, const std::vector<Camera>& scan) {
  SoakPath p;
  p.cameras = i % 2 == 0 ? &orbit : &scan;
  p.ping_pong = i % 2 == 1;
  p.reversed = i % 4 >= 2;
  p.phase = size_t(i) * 97 % p.cameras->size();
  p.name = std::string(i % 2 == 0 ? "orbit" : "scan") + (p.reversed ? " reversed" : "");
  return p;
}

SoakClientLog run_soak_client(const SoakClientPlan& plan, uint32_t minutes) {
  SoakClientLog log;
  log.minutes.resize(minutes);
  // mt19937_64's output is fixed by the standard (the distributions' are not): the same draws everywhere.
  std::mt19937_64 rng(plan.seed);
  const auto reconnect_delay = [&] {
    return std::chrono::milliseconds(kReconnectMinMs + rng() % (kReconnectMaxMs - kReconnectMinMs + 1));
  };
  // The first drop comes as if the client had been connected for a while already: the residual time of
  // the renewal process (an interval drawn with odds in proportion to its length, then a point in it).
  // Otherwise no client would drop in the first 30 s and they would all come in a wave after.
  const auto first_drop_delay = [&] {
    for (;;) {
      const auto interval = reconnect_delay();
      if (rng() % kReconnectMaxMs < uint64_t(interval.count()))
        return std::chrono::milliseconds(rng() % uint64_t(interval.count() + 1));
    }
  };
  const auto minute_at = [&](Clock::time_point t) -> SoakMinute& {
    const double m = std::max(0.0, seconds_between(plan.t0, t)) / 60;
    return log.minutes[std::min<size_t>(size_t(m), minutes - 1)];
  };
  client::LoadClientOptions options;
  options.answer_timeout = kAnswerTimeout;
  options.model = plan.data;
  client::LoadClient client("127.0.0.1", plan.port, plan.model, options);
  const auto period =
      std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1 / kSoakFramesPerSecond));
  Clock::time_point next_frame = plan.start;
  Clock::time_point next_drop = plan.start + first_drop_delay();
  bool resume = false;
  std::this_thread::sleep_until(next_frame);
  while (Clock::now() < plan.end) {
    try {
      if (!client.connected()) {
        const Clock::time_point begun = Clock::now();
        const bool resuming = resume && client.holds_splits();
        client.open(resuming);
        SoakMinute& minute = minute_at(begun);
        minute.open_ms.push_back(1000 * seconds_between(begun, Clock::now()));
        ++(resuming ? minute.resumes : minute.fresh);
      }
      const Clock::time_point sent = Clock::now();
      const uint64_t before = client.splits_received();
      const double ms = client.view(plan.path.at(log.frames), plan.tolerance);
      SoakMinute& minute = minute_at(sent);
      minute.view_ms.push_back(ms);
      minute.splits += client.splits_received() - before;
      ++log.frames;
    } catch (const Error& e) {
      // Whatever went wrong ended this session only: count it and come back on the leaves held (they
      // hold only splits that were checked), as a viewer that lost its server does.
      const Clock::time_point now = Clock::now();
      ++minute_at(now).failures;
      if (log.failures.size() < kFailuresKept)
        log.failures.push_back(fixed(seconds_between(plan.t0, now), 1) + " s: " + e.what());
      client.drop();
      resume = true;
    }
    const Clock::time_point now = Clock::now();
    if (now >= next_drop && client.connected()) {
      client.drop();
      ++minute_at(now).reconnects;
      resume = rng() % 2 == 0;
      next_drop = now + reconnect_delay();
    }
    // A late answer delays the next frame instead of sending a burst to catch up.
    next_frame = std::max(next_frame + period, now);
    std::this_thread::sleep_until(next_frame);
  }
  plan.release.wait();
  return log;
}

}  // namespace pms::bench
