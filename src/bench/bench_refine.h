// Parts of the "refine" group shared by its files (bench_refine.cpp, bench_refine_srmesh.cpp).
#pragma once
#include <nlohmann/json.hpp>
#include <string>

#include "bench/bench.h"
#include "common/camera.h"
#include "spm/hierarchy.h"
#include "spm/path_refinement.h"  // complete_hierarchy
#include "spm/vertex_hierarchy.h"

namespace pms::bench {

// Writes `text` to stdout at once: tables show as they fill.
void print_now(const std::string& text);

// Issue 18's cameras: eye = c + d·r·(sin a, 0, cos a), c the box centre and r half its diagonal, looking at
// c, up +y, 1920 x 1080, 60° vertical field of view.
Camera srmesh_camera(const ModelData& model, float distance, float angle_deg);

// Issue 18's table: bunny at four camera distances beside Hoppe's SrMesh (constants measured with his
// code), and the same timings on dragon. Appends to `out` under "srmesh".
std::string srmesh_comparison_section(const BenchContext& context, nlohmann::json& out);

}  // namespace pms::bench
