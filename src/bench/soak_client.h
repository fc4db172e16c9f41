// One client of the soak (bench_soak.cpp): a LoadClient that flies its own path at a steady frame rate
// for the whole soak, drops its connection at random moments and comes back, half the time resuming
// on the leaves it holds and half the time as a new viewer, and logs what it saw minute by minute.
#pragma once
#include <chrono>
#include <cstdint>
#include <future>
#include <string>
#include <vector>

#include "common/camera.h"
#include "spm/hierarchy.h"

namespace pms::bench {

// Frames per second each client asks for: a steady load, well under what the server can answer.
constexpr double kSoakFramesPerSecond = 4;

// A camera path flown in a loop from `phase`: an orbit goes round, a scan goes up and comes back down.
struct SoakPath {
  std::string name;  // "orbit" or "scan", and "reversed"
  const std::vector<Camera>* cameras = nullptr;
  bool ping_pong = false;
  bool reversed = false;
  size_t phase = 0;
  const Camera& at(uint64_t frame) const;
  // Client i's own path: orbits and scans alternate, each from its own phase, half of each reversed.
  static SoakPath of_client(uint32_t i, const std::vector<Camera>& orbit, const std::vector<Camera>& scan);
};

struct SoakMinute {
  std::vector<double> view_ms;  // VIEW sent -> its final batch, by the minute it was sent in
  std::vector<double> open_ms;  // connect, HELLO, OPEN -> BASE (a resume rebuilds the server's tags here)
  uint32_t failures = 0, fresh = 0, resumes = 0, reconnects = 0;
  uint64_t splits = 0;
};

struct SoakClientLog {
  std::vector<SoakMinute> minutes;
  uint64_t frames = 0;
  std::vector<std::string> failures;  // the first few, "12.3 s: what"
};

struct SoakClientPlan {
  uint16_t port = 0;
  std::string model;
  const ModelData* data = nullptr;  // the model served, for the leaves a resume sends
  SoakPath path;
  uint64_t seed = 0;                                 // reconnect times and resume-or-new draws
  std::chrono::steady_clock::time_point start, end;  // the client's first frame; no VIEW is sent after end
  std::chrono::steady_clock::time_point t0;          // the soak's start, minute 1 begins here
  float tolerance = 1;
  // After `end` the client keeps its connection until this is ready: the soak's last sample is taken
  // with every session still there.
  std::shared_future<void> release;
};

// Runs one client until plan.end; failures are counted, not thrown (the client reconnects and goes on).
SoakClientLog run_soak_client(const SoakClientPlan& plan, uint32_t minutes);

}  // namespace pms::bench
