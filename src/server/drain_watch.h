// Whether a peer reads what it was sent (the TCP and the HTTP server's write deadline): a write that
// succeeded only moved bytes into the kernel, so progress is what the peer acknowledged (written - unsent,
// io_threads.h). The watch runs while bytes wait and starts again each time the peer has taken enough of
// them. A trickle does not count: a kernel that has merged its full receive queue takes a few bytes now and
// then from a peer that never reads. Progress is only seen when looked for, so the owner looks kLooks times
// per deadline (next_look): a peer is then closed within 1 + 1/kLooks deadlines of the last bytes it took.
#pragma once
#include <algorithm>
#include <chrono>
#include <cstdint>

namespace pms::server {

class DrainWatch {
 public:
  using Clock = std::chrono::steady_clock;

  // What a peer must take per deadline for it to count as reading (or all it was sent, if less).
  static constexpr uint64_t kMinProgressBytes = 1024;
  static constexpr int kLooks = 8;

  explicit DrainWatch(uint32_t deadline_ms) : deadline_(std::chrono::milliseconds(deadline_ms)) {}

  bool running() const { return running_; }
  // Bytes wait: starts the watch unless it runs; `taken` is what the peer has acknowledged so far.
  void start(Clock::time_point now, uint64_t taken) {
    if (running_) return;
    running_ = true;
    since_ = looked_ = now;
    taken_ = taken;
  }
  void stop() { running_ = false; }
  // When the owner must look next (only while running).
  Clock::time_point next_look() const {
    const auto between = std::max<Clock::duration>(deadline_ / kLooks, std::chrono::milliseconds(1));
    return std::min(since_ + deadline_, looked_ + between);
  }
  // Looks at the peer's progress: `taken` of `written` acknowledged now. True when it has taken too little
  // for a whole deadline; the watch stops once everything is across and `more_to_send` is false.
  bool stalled(Clock::time_point now, uint64_t taken, uint64_t written, bool more_to_send) {
    looked_ = now;
    if (taken >= taken_ + std::min<uint64_t>(kMinProgressBytes, written - std::min(written, taken_))) {
      taken_ = taken;
      since_ = now;
    }
    if (!more_to_send && taken == written) running_ = false;
    return running_ && now >= since_ + deadline_;
  }

 private:
  Clock::duration deadline_;
  bool running_ = false;
  Clock::time_point since_{};   // bytes wait, and the peer has taken too few of them since
  Clock::time_point looked_{};  // when its progress was last looked at
  uint64_t taken_ = 0;          // bytes it had taken then
};

}  // namespace pms::server
