// One group of HTTP attack classes against a real `pmstream serve --json` child (http_attackers.h): a
// good receiver-driven client from 127.0.0.1 flies a path in quiet, then again while every class of the
// group attacks at once from 127.0.0.2 ... 127.0.0.5, and the server is watched from outside throughout.
// The short test (tests/bench/http_attacks_test.cpp) and the bench's attacks group both run this.
#pragma once
#include <chrono>
#include <cstdint>
#include <deque>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "bench/http_attackers.h"
#include "bench/mesh_faces.h"
#include "common/camera.h"

namespace pms::bench {

struct AttackSetup {
  std::string pmstream_exe, model_pms, model_name;
  std::string model_path;      // "/models/NAME/VERSION", where its resources are
  std::vector<Camera> path;
  float tolerance = 1;
  std::string expensive;       // the most expensive split request's URL (http_attack_targets.h)
  std::string expensive_note;  // how many ids, the depth, the splits and the URL's length
  // The server's deadlines (--http-*-timeout-ms), also what the attackers expect of it.
  std::chrono::milliseconds request_timeout{10000}, write_timeout{10000}, idle_timeout{30000};
  std::chrono::milliseconds slack{1500};  // AttackTarget::slack
  int attackers_per_class = 10;
  std::chrono::milliseconds min_attack{0};  // an attack lasts this at least, and until the flight lands
  bool compare_p99 = true;                  // fly pairs again while the ratio is over kMaxP99Ratio
};

constexpr double kMaxP99Ratio = 3;  // attacked / quiet

struct AttackFlight {
  std::vector<double> latency_ms;  // per split request: GET handed over to its answer read
  std::vector<IdFace> mesh;        // at the end of the path
  double seconds = 0;
  std::string error;  // the client failed
};

struct AttackOutcome {
  std::string group;
  std::vector<AttackClass> classes;
  std::deque<AttackTally> tallies;  // per class, in `classes` order
  AttackFlight quiet, attacked;     // the last pair flown
  double median_ratio = 0;          // of the attacked / quiet p99 ratios of the pairs flown
  size_t pairs = 0;
  bool same_mesh = false;   // every attacked flight ended with the quiet flight's mesh
  double attack_cpu_s = 0;  // the server's CPU during the (last) attack
  uint64_t quiet_rss = 0;   // after the quiet flight
  uint64_t peak_rss = 0, peak_sockets = 0, peak_total = 0;
  uint64_t memory_bound = 0;               // quiet_rss + the server's socket_buffer_bound_bytes
  double idle_after_s = -1, idle_use = 0;  // attack's end to a second under 10 % of a core; that second's use
  double sigterm_s = 0;
  nlohmann::json http;  // the server's http counters after the attack, less those before it
  std::string error;    // the server or the run failed
};

double p99(const std::vector<double>& samples);

AttackOutcome run_attack_group(const AttackSetup& setup, const AttackGroup& group);

}  // namespace pms::bench
