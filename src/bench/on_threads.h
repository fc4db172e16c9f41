// The flights' viewers each on a thread of their own (failover_flight.h, tier_flight.h).
#pragma once
#include <cstddef>
#include <functional>
#include <thread>
#include <vector>

namespace pms::bench {

// Runs fn(0) .. fn(count - 1) at once, each on a thread of its own; returns once every one has.
inline void on_threads(size_t count, const std::function<void(size_t)>& fn) {
  std::vector<std::thread> threads;
  threads.reserve(count);
  for (size_t i = 0; i < count; ++i) threads.emplace_back(fn, i);
  for (std::thread& t : threads) t.join();
}

}  // namespace pms::bench
