// The workers that build served models' tables (model_tables.h) when a session first needs them: at most
// `max_running` builds at once, the rest queued. A model's mode is queued at most once, so the queue holds
// at most models × modes entries whatever peers ask; a build that failed stays failed. Waiters are
// callbacks run on the worker when the build settles; they must only hand the news to their own thread
// (asio::post), never block or call back in here.
#pragma once
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "server/model_tables.h"
#include "server/served_mode.h"

namespace pms::server {

struct ServedModel;

// Counters for `serve --json` (docs/operating.md).
struct TableBuildStats {
  std::atomic<uint64_t> started{0}, failed{0};
  std::atomic<uint64_t> running{0}, peak_running{0};  // builds running now, and the most at once
  std::atomic<uint64_t> waits{0};                     // requests that found their tables not ready
};

// Who waits: `owner` (a session or a connection) is forgotten when it ends, `group` (a server) when it stops.
struct TableWaiter {
  const void* owner = nullptr;
  const void* group = nullptr;
  std::function<void()> wake;
};

class TableBuilds {
 public:
  explicit TableBuilds(uint32_t max_running);
  ~TableBuilds();  // waits for the running builds; queued ones are dropped
  TableBuilds(const TableBuilds&) = delete;
  TableBuilds& operator=(const TableBuilds&) = delete;

  // True when `mode`'s tables of `model` are ready. Otherwise queues their build if none was queued (not
  // after a failure), and unless they failed, registers `waiter`, woken once when the build settles.
  bool request(const ServedModel& model, ServedMode mode, TableWaiter waiter);
  // No wake of this owner (or group) runs once these return.
  void forget_owner(const void* owner);
  void forget_group(const void* group);
  // Blocks until `mode`'s tables of `model` settle, ready or failed (a session with no transport to wake it).
  void wait(const ServedModel& model, ServedMode mode);
  // Queues `modes` of every model given (those not built or queued yet), without waiting.
  void queue_all(const std::vector<const ServedModel*>& models, ModeSet modes);
  // Builds `modes` of every model given and waits for them; pms::Error naming the model and the mode for
  // the first that failed.
  void build_all(const std::vector<const ServedModel*>& models, ModeSet modes);

  uint32_t max_running() const { return uint32_t(workers_.size()); }
  const TableBuildStats& stats() const { return stats_; }

 private:
  struct Job {
    std::shared_ptr<const ServedModel> model;  // a model a reload dropped lives until its build ends
    ServedMode mode;
  };
  struct Waiting {
    ModelTables* tables;
    ServedMode mode;
    TableWaiter waiter;
  };
  // Under mutex_: queues the build if it is absent; false when it failed.
  bool queue_locked(const ServedModel& model, ServedMode mode);
  void work();
  void run(const Job& job);

  std::mutex mutex_;
  std::condition_variable jobs_ready_, settled_;
  std::deque<Job> jobs_;
  std::vector<Waiting> waiting_;
  bool stopping_ = false;
  TableBuildStats stats_;
  std::vector<std::thread> workers_;
};

}  // namespace pms::server
