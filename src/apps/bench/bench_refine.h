// Parts of the "refine" group shared by its files (bench_refine.cpp, bench_refine_srmesh.cpp).
#pragma once
#include <nlohmann/json.hpp>
#include <string>

#include "apps/bench/bench.h"
#include "pm/hierarchy.h"
#include "refine/vertex_hierarchy.h"

namespace pms::app {

// Writes `text` to stdout at once: tables show as they fill.
void print_now(const std::string& text);

// Every split known: the loop's cost alone, with nothing to fetch.
VertexHierarchy complete_hierarchy(const ModelData& model);

// Issue 18's table: bunny at four camera distances beside Hoppe's SrMesh (constants measured with his
// code), and the same timings on dragon. Appends to `out` under "srmesh".
std::string srmesh_comparison_section(const BenchContext& context, nlohmann::json& out);

}  // namespace pms::app
