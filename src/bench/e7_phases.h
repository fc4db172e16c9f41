// E7's breakdown by phase (cheng-ooi Table 1, "Comparison of CPU usage of the sender"): where a server's time
// goes while one client flies the orbit, sender- and receiver-driven, beside the paper's seconds for Happy
// Buddha. The servers run with `serve --profile-phases` (server/phase_times.h), in flights of their own, so
// the timers never touch E7's CPU per split.
#pragma once
#include <array>
#include <cstddef>
#include <nlohmann/json.hpp>
#include <string>

#include "bench/report.h"
#include "server/phase_times.h"

namespace pms::bench {

using PhaseMs = std::array<double, size_t(server::Phase::count)>;

// One profiled flight's server: its CPU over the flight and the time of each phase, in milliseconds.
struct PhaseCost {
  double cpu_ms = 0;
  PhaseMs phase_ms{};
  std::string error;  // the flight failed: no figures
};

// The phases_ms object of a `serve --json` stats line.
PhaseMs phase_ms_of(const nlohmann::json& phases);

Table e7_phase_table();
// One row per paper phase for `model`, and its total.
void add_e7_phase_rows(const std::string& model, const PhaseCost& sender, const PhaseCost& receiver, Table& table);
nlohmann::json e7_phase_record(const PhaseCost& sender, const PhaseCost& receiver);
// What the table's rows and columns are.
std::string e7_phase_notes();

}  // namespace pms::bench
