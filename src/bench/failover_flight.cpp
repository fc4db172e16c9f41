#include "bench/failover_flight.h"

#include <condition_variable>
#include <exception>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>
#include <utility>

#include "bench/on_threads.h"
#include "common/error.h"
#include "spm/vertex_hierarchy.h"

namespace pms::bench {
namespace {

using Clock = std::chrono::steady_clock;

// Where the viewers meet the plan's event: all of them (held), or the first to come (not held). Either way
// it happens mid-flight, once every viewer has its session: a viewer still opening when an origin dies
// fails its first OPEN, which no viewer retries. A viewer that failed, or never gets to the event frame,
// leaves, so the others are not held for it.
class EventPoint {
 public:
  explicit EventPoint(const FailoverPlan& plan) : plan_(plan), viewers_(plan.viewers.size()) {}

  // The viewer has its session, or will never have one.
  void opened() {
    const std::lock_guard lock(mutex_);
    ++opened_;
    changed_.notify_all();
  }

  void arrive() {
    std::unique_lock lock(mutex_);
    ++arrived_;
    if (plan_.hold_viewers) {
      if (arrived_ == viewers_) return happen(lock);
      return changed_.wait(lock, [this] { return done_; });
    }
    if (std::exchange(claimed_, true)) return;  // another viewer runs it
    changed_.wait(lock, [this] { return opened_ == viewers_; });
    happen(lock);
  }

  void leave() {
    std::unique_lock lock(mutex_);
    if (++arrived_ == viewers_ && plan_.hold_viewers && !done_) happen(lock);
  }

 private:
  void happen(std::unique_lock<std::mutex>& lock) {
    lock.unlock();
    if (plan_.event) plan_.event();
    lock.lock();
    done_ = true;
    changed_.notify_all();
  }

  const FailoverPlan& plan_;
  const size_t viewers_;
  std::mutex mutex_;
  std::condition_variable changed_;
  size_t opened_ = 0, arrived_ = 0;
  bool claimed_ = false, done_ = false;
};

client::ClientOptions viewer_options(const FailoverPlan& plan, const FailoverViewerPlan& viewer) {
  client::ClientOptions options;
  options.tolerance = plan.tolerance;
  options.name = "pmstream-failover";
  options.reconnect_attempts = plan.reconnect_attempts;
  options.reconnect_delay = plan.reconnect_delay;
  options.websocket_path = viewer.websocket_path;
  return options;
}

void fly_one(const FailoverPlan& plan, size_t index, EventPoint& event, FailoverViewer& out,
             const std::function<void(size_t, client::StreamingClient&)>& at_end) {
  const FailoverViewerPlan& viewer = plan.viewers[index];
  bool opened = false, met_event = false;
  try {
    std::optional<Clock::time_point> lost_at;  // in the frame being flown
    uint64_t frame_began_with = 0;             // splits received before the frame
    client::StreamingClient* flying = nullptr;
    client::ClientOptions options = viewer_options(plan, viewer);
    options.on_reconnect = [&](const std::string&, uint32_t) {
      ++out.attempts;
      if (lost_at) return;
      lost_at = Clock::now();
      out.lost_mid_frame += flying->session().splits_received() > frame_began_with;
    };
    client::StreamingClient client("127.0.0.1", viewer.port, options, plan.model);
    flying = &client;  // reconnects happen in frames only
    out.opened = client.counters();
    opened = true;
    event.opened();
    for (size_t frame = 0; frame < viewer.path.size(); ++frame) {
      if (frame == plan.event_frame) {
        met_event = true;
        event.arrive();
      }
      lost_at.reset();
      frame_began_with = client.session().splits_received();
      client.frame(viewer.path[frame]);
      if (lost_at) out.resume_ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - *lost_at).count());
    }
    out.splits_received = client.session().splits_received();
    const VertexHierarchy& hierarchy = client.session().hierarchy();
    out.splits_held = (hierarchy.size() - hierarchy.root_count()) / 2;
    out.total = client.counters();
    if (at_end) at_end(index, client);
  } catch (const std::exception& e) {
    out.error = e.what();
  }
  if (!opened) event.opened();
  if (!met_event) event.leave();
}

}  // namespace

std::vector<FailoverViewer> fly_failover(const FailoverPlan& plan,
                                         const std::function<void(size_t, client::StreamingClient&)>& at_end) {
  std::vector<FailoverViewer> viewers(plan.viewers.size());
  EventPoint event(plan);
  on_threads(plan.viewers.size(), [&](size_t i) { fly_one(plan, i, event, viewers[i], at_end); });
  return viewers;
}

}  // namespace pms::bench
