// The server's time by the phases of cheng-ooi's Table 1 ("Comparison of CPU usage of the sender"), so the
// bench can put both modes' breakdown beside the paper's (E7). Off unless `serve --profile-phases`: a
// phase is timed by the monotonic clock on the I/O thread that runs it (a turn never blocks, so that is its
// CPU time), and an off switch costs one branch per timed block.
#pragma once
#include <array>
#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>

namespace pms::server {

// The paper's rows, in its order. The sender-driven server codes each split's ids with its record once per
// model (protocol/packet_table.h), so a session's "search vertex split" is a copy of the coded packet and
// its "encode IDs" is that same copy: the sender-driven mode times both as search_splits.
enum class Phase : uint8_t {
  send_base,             // BASE (and the code tables) queued or answered
  decode_ids,            // a receiver-driven request's id set decoded
  search_splits,         // the split records (packets) of the ids looked up and copied into the answer
  determine_visibility,  // the view's criteria evaluated over the front (qrefine)
  update_front,          // the front moved below the splits sent (and parked or unparked)
  count
};

constexpr const char* kPhaseNames[size_t(Phase::count)] = {"send_base", "decode_ids", "search_splits",
                                                             "determine_visibility", "update_front"};

struct PhaseTimes {
  std::array<std::atomic<uint64_t>, size_t(Phase::count)> ns{};
};

// Adds the time from construction to destruction to `times`'s phase; nothing when `times` is null.
class PhaseTimer {
 public:
  PhaseTimer(PhaseTimes* times, Phase phase) : times_(times), phase_(phase) {
    if (times_) start_ = std::chrono::steady_clock::now();
  }
  ~PhaseTimer() {
    if (!times_) return;
    const auto took = std::chrono::steady_clock::now() - start_;
    times_->ns[size_t(phase_)].fetch_add(uint64_t(std::chrono::nanoseconds(took).count()), std::memory_order_relaxed);
  }
  PhaseTimer(const PhaseTimer&) = delete;
  PhaseTimer& operator=(const PhaseTimer&) = delete;

 private:
  PhaseTimes* times_;
  Phase phase_;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace pms::server
