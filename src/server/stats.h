// A running server's counters, read by `serve --json` and the bench.
#pragma once
#include <atomic>
#include <cstdint>

#include "server/phase_times.h"

namespace pms::server {

struct ServerStats {
  std::atomic<uint64_t> sessions_opened{0}, sessions_active{0}, sessions_refused{0};
  std::atomic<uint64_t> sessions_timed_out{0};  // closed by a deadline (handshake, idle, frame, write)
  std::atomic<uint64_t> sessions_failed{0};     // ended by an internal fault (ERROR internal)
  std::atomic<uint64_t> protocol_errors{0};     // ERRORs for a peer's bad message or sequence
  std::atomic<uint64_t> bytes_in{0}, bytes_out{0}, splits_sent{0}, errors_sent{0};
  std::atomic<uint64_t> accept_failures{0};
  std::atomic<uint64_t> longest_turn_us{0};    // the longest one session held an I/O thread in one go
  std::atomic<uint64_t> peak_state_bytes{0};   // the largest Session::state_bytes() seen
  std::atomic<uint64_t> peak_buffer_bytes{0};  // the same without the client's front
  std::atomic<uint64_t> fronts_parked{0};      // sender-driven fronts coded once their session went idle
  PhaseTimes phases;                           // with ServerLimits::profile_phases
};

// The HTTP transport's counters (docs/operating.md, "The JSON lines").
struct HttpStats {
  std::atomic<uint64_t> connections_opened{0}, connections_active{0}, connections_refused{0};
  std::atomic<uint64_t> connections_refused_per_address{0};  // over --http-max-connections-per-address
  std::atomic<uint64_t> connections_reset{0};  // closed at a deadline with a reset, their unsent bytes dropped
  std::atomic<uint64_t> connections_timed_out{0};                        // closed by a deadline (idle, request, write)
  std::atomic<uint64_t> requests{0}, not_modified{0}, client_errors{0};  // 4xx answers
  std::atomic<uint64_t> bytes_in{0}, bytes_out{0}, splits_served{0};
  std::atomic<uint64_t> split_requests{0};  // 200s and 304s of the split resources (splits, blocks)
  std::atomic<uint64_t> budget_waits{0};    // times a connection was not read until its budgets refilled
  std::atomic<uint64_t> sliced_answers{0};  // answers whose body took more than one turn to build
  std::atomic<uint64_t> longest_turn_us{0};  // the longest one connection held an I/O thread in one go
  PhaseTimes phases;                         // with HttpLimits::profile_phases
};

// The WebSocket's counters beyond its sessions' (which are a ServerStats of their own): the upgrades and
// why some were refused (docs/operating.md, "The JSON lines").
struct WsStats {
  std::atomic<uint64_t> upgrades{0};                  // 101s: sessions begun
  std::atomic<uint64_t> refused_origin{0};            // 403: an Origin not allowed
  std::atomic<uint64_t> refused_full{0};              // 503: at the WebSocket sessions cap
  std::atomic<uint64_t> refused_malformed{0};         // 400/426: not a valid upgrade
  std::atomic<uint64_t> messages_refused{0};          // text, split or merged frames, pings past the rate
  std::atomic<uint64_t> budget_waits{0};              // times a session waited for its address's budget
};

// Raises `target` to `value` if it is larger, from any thread.
inline void update_max(std::atomic<uint64_t>& target, uint64_t value) {
  uint64_t seen = target.load(std::memory_order_relaxed);
  while (value > seen && !target.compare_exchange_weak(seen, value, std::memory_order_relaxed)) {
  }
}

}  // namespace pms::server
