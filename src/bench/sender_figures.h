// The sender group's figure experiments (kim-lee-kobbelt 2005 §8): E13, faces and times per frame along the
// look path (Fig. 8), and E14, the meshes three clients hold after the same bytes, rendered side by side
// (Fig. 10). Each returns its report section, prints its tables and adds its record to `out`.
#pragma once
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "bench/bench.h"
#include "bench/bench_model.h"

namespace pms::bench {

// E13 on `m`: a sender-driven client flies two laps of the look path; per frame its faces, its own CPU time
// (adaptation and applying what arrived), the server's, and the software renderer's time for its mesh.
std::string frame_costs_section(const BenchContext& context, const BenchModel& m, bool quick, nlohmann::json& out);

// E14 on each model: the sender-driven, sender-plain and view-independent clients' meshes after the same
// byte budget (0.5 MiB, and 0.5 MiB scaled by the model's splits over the paper's Buddha's), at the far
// and mid viewpoints, rendered side by side into PNGs beside the full mesh.
std::string budget_images_section(const BenchContext& context, const std::vector<BenchModel>& models, bool quick,
                                  nlohmann::json& out);

}  // namespace pms::bench
