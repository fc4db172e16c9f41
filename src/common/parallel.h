// Splits [0, count) into one contiguous range per core and runs them on threads, for loops whose
// iterations are independent. Below `min_parallel` items it runs inline: starting threads costs more.
// Built with PMSTREAM_NO_THREADS (the browser's core: emscripten without pthreads sets it), every range runs
// inline on the caller's thread, in order, with the same results.
#pragma once
#include <algorithm>
#include <cstddef>
#include <exception>
#include <vector>

#if defined(__EMSCRIPTEN__) && !defined(__EMSCRIPTEN_PTHREADS__) && !defined(PMSTREAM_NO_THREADS)
#define PMSTREAM_NO_THREADS 1
#endif
#ifndef PMSTREAM_NO_THREADS
#include <thread>
#endif

namespace pms {

// How many ranges for_each_range and map_ranges cut `count` items into.
inline size_t range_count([[maybe_unused]] size_t count, [[maybe_unused]] size_t min_parallel) {
#ifdef PMSTREAM_NO_THREADS
  return 1;
#else
  if (count < min_parallel) return 1;
  return std::clamp<size_t>(std::thread::hardware_concurrency(), 1, 8);
#endif
}

template <class Fn>  // fn(begin, end)
void for_each_range(size_t count, size_t min_parallel, Fn&& fn) {
  const size_t threads = range_count(count, min_parallel);
  if (threads == 1) {
    fn(size_t(0), count);
    return;
  }
#ifndef PMSTREAM_NO_THREADS
  std::vector<std::thread> workers;
  for (size_t i = 1; i < threads; ++i) workers.emplace_back(fn, count * i / threads, count * (i + 1) / threads);
  fn(size_t(0), count / threads);
  for (std::thread& w : workers) w.join();
#endif
}

// [0, count) cut into `ranges` contiguous ranges of equal size: their ranges + 1 bounds.
inline std::vector<size_t> even_bounds(size_t count, size_t ranges) {
  std::vector<size_t> bounds(ranges + 1);
  for (size_t i = 0; i <= ranges; ++i) bounds[i] = count * i / ranges;
  return bounds;
}

// fn(bounds[i], bounds[i + 1]) for every range, each on a thread of its own (the first on the caller's),
// with a result per range in range order. A range that throws does not stop the others; afterwards the
// first range's exception (in range order) is rethrown, which is the one a sequential loop over the
// ranges would have met first.
template <class Fn>
auto map_bounded_ranges(const std::vector<size_t>& bounds, Fn&& fn) -> std::vector<decltype(fn(size_t(0), size_t(0)))> {
  const size_t ranges = bounds.size() - 1;
  std::vector<decltype(fn(size_t(0), size_t(0)))> results(ranges);
  std::vector<std::exception_ptr> errors(ranges);
  const auto run = [&](size_t i) {
    try {
      results[i] = fn(bounds[i], bounds[i + 1]);
    } catch (...) {
      errors[i] = std::current_exception();
    }
  };
#ifdef PMSTREAM_NO_THREADS
  for (size_t i = 0; i < ranges; ++i) run(i);
#else
  std::vector<std::thread> workers;
  for (size_t i = 1; i < ranges; ++i) workers.emplace_back(run, i);
  run(0);
  for (std::thread& w : workers) w.join();
#endif
  for (const std::exception_ptr& error : errors)
    if (error) std::rethrow_exception(error);
  return results;
}

// for_each_range with a result per range: map_bounded_ranges over equal ranges.
template <class Fn>
auto map_ranges(size_t count, size_t min_parallel, Fn&& fn) -> std::vector<decltype(fn(size_t(0), size_t(0)))> {
  return map_bounded_ranges(even_bounds(count, range_count(count, min_parallel)), fn);
}

}  // namespace pms
