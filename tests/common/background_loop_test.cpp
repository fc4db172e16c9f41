// common/background_loop.h: every item runs exactly once, split between the loop's thread and the
// caller's wait(); the caller may do other work meanwhile; an exception on either side comes out of
// wait() and stops the loop taking chunks; a loop left running is abandoned safely on destruction.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <stdexcept>
#include <thread>
#include <vector>

#include "common/background_loop.h"

namespace pms {
namespace {

TEST(BackgroundLoop, RunsEveryItemOnceWhileTheCallerWorks) {
  for (size_t count : {size_t(0), size_t(1), size_t(255), size_t(256), size_t(100001)}) {
    std::vector<std::atomic<int>> runs(count);
    BackgroundLoop loop;
    loop.start(count, 256, [&](size_t begin, size_t end) {
      ASSERT_LE(end - begin, 256u);
      for (size_t i = begin; i < end; ++i) ++runs[i];
    });
    size_t busy = 0;  // the caller's own work, overlapping the loop
    for (size_t i = 0; i < 1000; ++i) busy += i;
    loop.wait();
    EXPECT_EQ(busy, 499500u);
    for (size_t i = 0; i < count; ++i) ASSERT_EQ(runs[i].load(), 1) << "item " << i << " of " << count;
  }
}

TEST(BackgroundLoop, StartingAgainFinishesTheLoopBefore) {
  BackgroundLoop loop;
  std::atomic<size_t> first{0}, second{0};
  loop.start(10000, 16, [&](size_t begin, size_t end) { first += end - begin; });
  loop.start(500, 16, [&](size_t begin, size_t end) {
    EXPECT_EQ(first.load(), 10000u);  // every item of the first loop is done before the second starts
    second += end - begin;
  });
  loop.wait();
  EXPECT_EQ(second.load(), 500u);
  loop.wait();  // nothing running: returns at once
}

TEST(BackgroundLoop, AnExceptionComesOutOfWaitAndStopsTheLoop) {
  BackgroundLoop loop;
  std::atomic<size_t> ran{0};
  loop.start(1000, 1, [&](size_t begin, size_t) {
    if (begin == 10) throw std::runtime_error("item 10");
    ++ran;
  });
  EXPECT_THROW(loop.wait(), std::runtime_error);
  EXPECT_LT(ran.load(), 1000u);
  // The loop is usable again afterwards.
  std::atomic<size_t> again{0};
  loop.start(100, 7, [&](size_t begin, size_t end) { again += end - begin; });
  EXPECT_NO_THROW(loop.wait());
  EXPECT_EQ(again.load(), 100u);
}

TEST(BackgroundLoop, DestroyingARunningLoopAbandonsWhatIsLeft) {
  std::atomic<size_t> ran{0};
  {
    BackgroundLoop loop;
    loop.start(1000000, 1, [&](size_t, size_t) {
      ++ran;
      std::this_thread::sleep_for(std::chrono::microseconds(1));  // all of them: a minute at least
    });
  }  // no wait(): the destructor stops the loop and joins its thread
  EXPECT_LT(ran.load(), 1000000u);
}

}  // namespace
}  // namespace pms
