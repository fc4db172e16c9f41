// Splits [0, count) into one contiguous range per core and runs them on threads, for loops whose
// iterations are independent. Below `min_parallel` items it runs inline: starting threads costs more.
#pragma once
#include <algorithm>
#include <cstddef>
#include <thread>
#include <vector>

namespace pms {

template <class Fn>  // fn(begin, end)
void for_each_range(size_t count, size_t min_parallel, Fn&& fn) {
  const size_t threads = std::clamp<size_t>(std::thread::hardware_concurrency(), 1, 8);
  if (count < min_parallel || threads == 1) {
    fn(size_t(0), count);
    return;
  }
  std::vector<std::thread> workers;
  for (size_t i = 1; i < threads; ++i) workers.emplace_back(fn, count * i / threads, count * (i + 1) / threads);
  fn(size_t(0), count / threads);
  for (std::thread& w : workers) w.join();
}

}  // namespace pms
