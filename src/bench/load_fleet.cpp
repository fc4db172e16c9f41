#include "bench/load_fleet.h"

#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <memory>

#include "apps/camera_path.h"
#include "bench/fleet_session.h"
#include "common/error.h"
#include "common/process_cpu.h"
#include "protocol/message_types.h"
#include "spm/split_codec.h"

namespace pms::bench {
namespace asio = boost::asio;
using nlohmann::json;
namespace {

// An orbit slow enough to look around at the fleet's frame rate; the scan up and down in as long.
constexpr uint32_t kOrbitFrames = 360, kScanFrames = 180;
constexpr size_t kFailuresKept = 5;

void print_line(const json& line) {
  std::printf("%s\n", line.dump().c_str());
  std::fflush(stdout);
}

std::vector<Camera> path(app::PathKind kind, const ModelData& model, uint32_t frames) {
  app::PathOptions options;
  options.frames = frames;
  return app::make_camera_path(kind, model, options);
}

class Fleet : public FleetListener {
 public:
  Fleet(const LoadFleetArgs& args, const server::ServedModel& served)
      : args_(args), signals_(io_, SIGUSR1, SIGTERM), sweep_(io_) {
    model_.served = &served;
    model_.positions = grid_positions(served.model(), served.context.grid.bits);
    model_.criteria = &served.tables->selective().criteria;
    model_.tolerance = args.tolerance;
    model_.answer_timeout = std::chrono::milliseconds(args.answer_timeout_ms);
    orbit_ = path(app::PathKind::orbit, served.model(), kOrbitFrames);
    scan_ = path(app::PathKind::scan, served.model(), kScanFrames);
    for (uint32_t i = 0; i < args.sessions; ++i)
      sessions_.push_back(std::make_unique<FleetSession>(io_, model_, SoakPath::of_client(args.first + i, orbit_, scan_),
                                                         counters_, *this));
  }

  void run() {
    started_ = FleetClock::now();
    for (uint32_t i = 0; i < args_.open_at_once; ++i) open_next();
    if (args_.sessions == 0) ready();
    wait_signal();
    sweep();
    io_.run();
    for (auto& s : sessions_) s->close();
  }

  void opened(FleetSession&) override { opening_done(); }
  void failed(FleetSession& s) override {
    if (failures_.size() < kFailuresKept) failures_.push_back(s.error());
    ++failed_;
    if (!is_ready_) opening_done();
  }
  void settled(FleetSession&, bool satisfied) override {
    if (!satisfied) ++unsatisfied_;
    if (++settled_ == flown_) step_done();
  }

 private:
  void open_next() {
    if (next_open_ < sessions_.size())
      sessions_[next_open_++]->start({asio::ip::make_address("127.0.0.1"), args_.port});
  }
  void opening_done() {
    ++opened_;
    open_next();
    if (opened_ == sessions_.size()) ready();
  }
  void ready() {
    is_ready_ = true;
    print_line({{"event", "ready"},
                {"sessions", sessions_.size()},
                {"failed", failed_},
                {"failures", failures_},
                {"seconds", seconds_since(started_)},
                {"first_views", counters_.first_views.to_json()},
                {"splits", counters_.splits},
                {"cpu_s", process_cpu_seconds(getpid())}});
  }

  void wait_signal() {
    signals_.async_wait([this](const boost::system::error_code& ec, int number) {
      if (ec) return;
      if (number == SIGTERM) return finish();
      start_step();
      wait_signal();
    });
  }

  // A step flies the first flying[k] sessions that have not failed, each from its own phase of the frame.
  void start_step() {
    if (!is_ready_ || stepping_ || step_ >= args_.flying.size()) {
      print_line({{"event", "step"}, {"error", "SIGUSR1 before ready, during a step or after the last step"}});
      return;
    }
    stepping_ = true;
    counters_ = FleetCounters{};
    unsatisfied_ = settled_ = flown_ = 0;
    failed_at_step_ = failed_;
    step_cpu_ = process_cpu_seconds(getpid());
    step_started_ = FleetClock::now();
    const uint32_t wanted = std::min<uint32_t>(args_.flying[step_], uint32_t(sessions_.size()));
    for (uint32_t i = 0; i < wanted; ++i) {
      if (sessions_[i]->failed()) continue;
      sessions_[i]->fly(std::chrono::microseconds(1'000'000 / 30) * (i % 30) / 30);
      flying_.push_back(sessions_[i].get());
    }
    flown_ = flying_.size();
    const auto step_time = std::chrono::duration_cast<FleetClock::duration>(std::chrono::duration<double>(args_.step_seconds));
    auto timer = std::make_shared<asio::steady_timer>(io_, step_time);
    timer->async_wait([this, timer](const boost::system::error_code&) {
      if (flown_ == 0) return step_done();
      for (FleetSession* s : std::vector<FleetSession*>(flying_)) s->stop_flying();
    });
  }

  void step_done() {
    print_line({{"event", "step"},
                {"step", step_},
                {"flying", flown_},
                {"views", counters_.views.to_json()},
                {"views_sent", counters_.views_sent},
                {"frames", counters_.frames},
                {"frames_waiting", counters_.frames_waiting},
                {"unsatisfied", unsatisfied_},
                {"failed", failed_ - failed_at_step_},
                {"failures", failures_},
                {"splits", counters_.splits},
                {"cpu_s", process_cpu_seconds(getpid()) - step_cpu_},
                {"seconds", seconds_since(step_started_)}});
    flying_.clear();
    stepping_ = false;
    ++step_;
  }

  void finish() {
    uint64_t splits = 0;
    for (auto& s : sessions_) {
      splits += s->splits();
      s->close();
    }
    print_line({{"event", "done"}, {"failed", failed_}, {"failures", failures_}, {"splits", splits}});
    io_.stop();
  }

  // Sessions waiting for the server past their deadline fail, a second at a time.
  void sweep() {
    sweep_.expires_after(std::chrono::seconds(1));
    sweep_.async_wait([this](const boost::system::error_code& ec) {
      if (ec) return;
      const FleetClock::time_point now = FleetClock::now();
      for (auto& s : sessions_) s->check_deadline(now);
      sweep();
    });
  }

  static double seconds_since(FleetClock::time_point t) {
    return std::chrono::duration<double>(FleetClock::now() - t).count();
  }

  const LoadFleetArgs& args_;
  asio::io_context io_;
  asio::signal_set signals_;
  asio::steady_timer sweep_;
  FleetModel model_;
  FleetCounters counters_;
  std::vector<Camera> orbit_, scan_;
  std::vector<std::unique_ptr<FleetSession>> sessions_;
  size_t next_open_ = 0, opened_ = 0;
  bool is_ready_ = false, stepping_ = false;
  size_t step_ = 0;
  std::vector<FleetSession*> flying_;
  size_t flown_ = 0, settled_ = 0;
  uint64_t failed_ = 0, failed_at_step_ = 0, unsatisfied_ = 0;
  std::vector<std::string> failures_;
  double step_cpu_ = 0;
  FleetClock::time_point started_, step_started_;
};

}  // namespace

void run_load_fleet(const LoadFleetArgs& args) {
  server::TableOptions tables;
  tables.preload = server::ModeSet().set(server::index_of(server::ServedMode::sender));
  const auto catalogue = server::Catalogue::open(
      {args.pms}, args.position_bits ? args.position_bits : protocol::kDefaultPositionBits, tables);
  const server::ServedModel& served = *catalogue->models().front();
  Fleet fleet(args, served);
  fleet.run();
}

}  // namespace pms::bench
