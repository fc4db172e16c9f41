// E9's N chosen from the frame time left (zheng-chan 2006 §7's future work; client/dag_management.h): the
// priority traversal in BUDGET mode along each route with fixed N and with the client's automatic N, each
// frame timed as the client sees it (DAG_VIEW sent to its answer applied, the session in this process), its
// mesh every 5 frames against the view's converged mesh.
#pragma once
#include <string>
#include <vector>

#include "bench/bench.h"
#include "bench/bench_model.h"
#include "common/camera.h"

namespace pms::bench {

struct DagRoute {
  std::string name;  // "route 1", "route 2"
  std::string label;  // what it is, for the tables
  std::vector<Camera> cameras;
};

// The section's markdown (tables and a plot per route) and its JSON under out["frame_budget"].
std::string dag_frame_budget_section(const BenchContext& context, const BenchModel& m,
                                     const std::vector<DagRoute>& routes, nlohmann::json& out);

}  // namespace pms::bench
