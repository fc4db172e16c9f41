// `pmstream-bench load-fleet`: one process, one thread, thousands of sender-driven sessions (fleet_session.h)
// against a server, as the fleet experiment (bench_fleet.cpp) runs several of them on a core of their own.
// It reports in JSON lines on stdout:
//   {"event":"ready", ...}  once every session has opened and had its first VIEW answered (or failed);
//   {"event":"step", ...}   after each SIGUSR1: the first flying[k] sessions flew for step_seconds, then
//                           settled on their last camera; VIEW latencies as a LatencyHistogram;
//   {"event":"done", ...}   after SIGTERM, every session closed.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

namespace pms::bench {

struct LoadFleetArgs {
  std::string pms;  // the model file the server serves, mapped here for its hierarchy and criteria
  uint16_t port = 0;
  uint32_t sessions = 100;
  uint32_t first = 0;               // the first session's index in the whole fleet: its path and phase
  std::vector<uint32_t> flying;     // per step, how many of this process's sessions fly
  double step_seconds = 10;
  uint32_t open_at_once = 16;       // sessions between connect and their first answer at once
  float tolerance = 1;
  uint32_t position_bits = 0;       // the server's --position-bits; 0: its default
  uint32_t answer_timeout_ms = 60000;
};

// Runs until SIGTERM; pms::Error for a model that cannot be opened.
void run_load_fleet(const LoadFleetArgs& args);

}  // namespace pms::bench
