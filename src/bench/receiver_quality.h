// The receiver group's image-quality experiments on its models: E6, PSNR against bytes received for the
// four streaming modes and the area-ranking receiver client (the plain records) toward one view
// (kim-lee-kobbelt Fig. 10; cheng-ooi Fig. 8), with a plot per model and
// view; and E8, error pixels and PSNR when the receiver-driven client fetches only the visible splits
// (cheng-ooi Table 2).
#pragma once
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "bench/bench.h"
#include "bench/bench_model.h"

namespace pms::bench {

// Runs E6 and E8 on every model, adds each model's samples to `records[i]` (the group's JSON record of
// models[i]) and returns the report's sections. A client that fails is a failure of the run (context.failures).
std::string e6_e8_sections(BenchContext& context, const std::vector<BenchModel>& models, nlohmann::json& records);

}  // namespace pms::bench
