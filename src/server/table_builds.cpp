// Table builds on worker threads, never on an I/O thread (table_builds.h).
#include "server/table_builds.h"

#include <malloc.h>

#include <algorithm>

#include "common/error.h"
#include "server/catalogue.h"

namespace pms::server {

using State = ModelTables::State;

TableBuilds::TableBuilds(uint32_t max_running) {
  if (max_running == 0) fail("--max-table-builds", "must be at least 1");
  for (uint32_t i = 0; i < max_running; ++i) workers_.emplace_back([this] { work(); });
}

TableBuilds::~TableBuilds() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
    jobs_.clear();
    waiting_.clear();
  }
  jobs_ready_.notify_all();
  for (std::thread& worker : workers_) worker.join();
}

bool TableBuilds::queue_locked(const ServedModel& model, ServedMode mode) {
  ModelTables& tables = *model.tables;
  const State state = tables.state(mode);
  if (state == State::failed) return false;
  if (state == State::absent) {
    tables.set_state(mode, State::queued);
    jobs_.push_back({model.shared_from_this(), mode});
    jobs_ready_.notify_one();
  }
  return true;
}

bool TableBuilds::request(const ServedModel& model, ServedMode mode, TableWaiter waiter) {
  if (model.tables->ready(mode)) return true;
  std::lock_guard<std::mutex> lock(mutex_);
  if (model.tables->ready(mode)) return true;  // settled since
  stats_.waits++;
  if (queue_locked(model, mode) && waiter.wake) waiting_.push_back({model.tables.get(), mode, std::move(waiter)});
  return false;
}

void TableBuilds::forget_owner(const void* owner) {
  std::lock_guard<std::mutex> lock(mutex_);
  std::erase_if(waiting_, [&](const Waiting& w) { return w.waiter.owner == owner; });
}

void TableBuilds::forget_group(const void* group) {
  std::lock_guard<std::mutex> lock(mutex_);
  std::erase_if(waiting_, [&](const Waiting& w) { return w.waiter.group == group; });
}

void TableBuilds::wait(const ServedModel& model, ServedMode mode) {
  std::unique_lock<std::mutex> lock(mutex_);
  queue_locked(model, mode);
  settled_.wait(lock, [&] {
    const State state = model.tables->state(mode);
    return state == State::ready || state == State::failed;
  });
}

void TableBuilds::queue_all(const std::vector<const ServedModel*>& models, ModeSet modes) {
  std::lock_guard<std::mutex> lock(mutex_);
  for (const ServedModel* model : models)
    for (size_t m = 0; m < kServedModeCount; ++m)
      if (modes.test(m)) queue_locked(*model, served_mode_at(m));
}

void TableBuilds::build_all(const std::vector<const ServedModel*>& models, ModeSet modes) {
  queue_all(models, modes);
  for (const ServedModel* model : models)
    for (size_t m = 0; m < kServedModeCount; ++m) {
      if (!modes.test(m)) continue;
      const ServedMode mode = served_mode_at(m);
      wait(*model, mode);
      if (model->tables->state(mode) == State::failed)
        fail(model->path,
             std::string("building its ") + served_mode_name(mode) + " tables: " + model->tables->failure(mode));
    }
}

void TableBuilds::work() {
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    jobs_ready_.wait(lock, [this] { return stopping_ || !jobs_.empty(); });
    if (stopping_) return;
    Job job = std::move(jobs_.front());
    jobs_.pop_front();
    job.model->tables->set_state(job.mode, State::building);
    stats_.started++;
    const uint64_t running = ++stats_.running;
    stats_.peak_running.store(std::max(stats_.peak_running.load(), running));
    lock.unlock();
    run(job);
    job = {};  // a model a reload dropped is freed here, outside the lock
    lock.lock();
    stats_.running--;
  }
}

// Builds one model's mode, then settles it and wakes its waiters (under the lock, so a forgotten owner is
// never woken after forget_owner returns).
void TableBuilds::run(const Job& job) {
  ModelTables& tables = *job.model->tables;
  State settled = State::ready;
  try {
    tables.build(*job.model, job.mode);
  } catch (const std::exception& e) {
    tables.failures_[index_of(job.mode)] = e.what();
    settled = State::failed;
  }
  // A build's scratch (a derivation refines the whole model) is freed, but glibc keeps it mapped: give it
  // back, so the memory a server reports is its tables'.
  malloc_trim(0);
  std::lock_guard<std::mutex> lock(mutex_);
  if (settled == State::failed) stats_.failed++;
  tables.set_state(job.mode, settled);
  std::vector<Waiting> woken;
  std::erase_if(waiting_, [&](Waiting& w) {
    if (w.tables != &tables || w.mode != job.mode) return false;
    woken.push_back(std::move(w));
    return true;
  });
  for (Waiting& w : woken) w.waiter.wake();
  settled_.notify_all();
}

}  // namespace pms::server
