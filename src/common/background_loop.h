// A loop over [0, count) that runs on a thread of its own while the caller goes on with other work,
// in chunks taken from a shared counter; wait() has the caller take chunks too until none are left.
// For work whose inputs the caller no longer changes: the builder computes one balanced round's
// refinement info while its single-threaded acceptance loop collapses the next round.
#pragma once
#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <functional>
#include <thread>
#include <utility>

namespace pms {

class BackgroundLoop {
 public:
  BackgroundLoop() = default;
  BackgroundLoop(const BackgroundLoop&) = delete;
  BackgroundLoop& operator=(const BackgroundLoop&) = delete;
  // Abandons what is left (an exception is unwinding past the owner): no item starts after this.
  ~BackgroundLoop() {
    next_ = count_;
    if (thread_.joinable()) thread_.join();
  }

  // fn(begin, end) over [0, count) in chunks of `chunk`; waits for the loop before first.
  void start(size_t count, size_t chunk, std::function<void(size_t, size_t)> fn) {
    wait();
    fn_ = std::move(fn);
    count_ = count;
    chunk_ = std::max<size_t>(chunk, 1);
    next_ = 0;
    thread_ = std::thread([this] {
      try {
        run();
      } catch (...) {
        error_ = std::current_exception();
        next_ = count_;
      }
    });
  }

  // Returns once every item is done, having run the ones left on this thread too. An exception stops
  // the loop taking chunks and is rethrown here: this thread's if it met one, else the loop thread's.
  void wait() {
    if (!thread_.joinable()) return;
    std::exception_ptr error;
    try {
      run();
    } catch (...) {
      error = std::current_exception();
      next_ = count_;
    }
    thread_.join();
    if (!error) error = std::exchange(error_, nullptr);
    error_ = nullptr;
    if (error) std::rethrow_exception(error);
  }

 private:
  void run() {
    for (size_t begin; (begin = next_.fetch_add(chunk_)) < count_;) fn_(begin, std::min(begin + chunk_, count_));
  }

  std::function<void(size_t, size_t)> fn_;
  size_t count_ = 0, chunk_ = 1;
  std::atomic<size_t> next_{0};
  std::exception_ptr error_;
  std::thread thread_;
};

}  // namespace pms
