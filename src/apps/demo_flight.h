// The streaming half of `pmstream demo`: an in-process server on loopback, a headless client flying
// over the model, a live progress line, a final table, snapshots and a report in the output directory.
#pragma once
#include <cstdint>
#include <string>

namespace pms::app {

struct FlightOptions {
  std::string out_dir = "demo-out";
  uint32_t frames = 240;
  float tolerance = 1;
  uint32_t snapshot_every = 40;  // frames between PNG snapshots (0 = none)
};

// Streams `pms_path` (served as `model_name`) along a low flight over its bounding box (for a terrain:
// across it, looking ahead and down; for any other model: the orbit path). Prints the table.
void run_demo_flight(const std::string& pms_path, const std::string& model_name, const FlightOptions& options);

}  // namespace pms::app
