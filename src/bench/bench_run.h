// One run of pmstream-bench: the chosen groups, one after another, each writing its report.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

namespace pms::bench {

struct BenchArgs {
  bool quick = false;
  std::vector<std::string> models, only;
  std::string shared, out = "bench-out", pmstream;
  uint32_t soak_clients = 100, soak_minutes = 10;
  uint32_t fleet_sessions = 5000, fleet_processes = 4;
  std::vector<std::string> fleet_flying;  // empty: the group's default
  double fleet_step_seconds = 10;
};

// "build, refine, ...": every group's name, for --help and errors.
std::string group_names();

// Runs the groups of args.only (default all) into args.out; pms::Error on bad arguments, before anything
// runs, and after the reports are written when a figure could not be measured.
void run_bench(const BenchArgs& args);

}  // namespace pms::bench
