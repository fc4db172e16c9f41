// gueziec et al. 1999's figures that are pictures, rendered from our models for E10 (report.md lists them):
// Fig. 1, a model's LODs nearest the paper's triangle counts; Fig. 11, the LODs of vertex clusterings and a
// geomorph between two of them; Fig. 15, a selective refinement through the DAG of collapses beside the
// full and the coarsest mesh. Each triangle is drawn in a shade of its own so the tessellation shows.
#pragma once
#include <filesystem>
#include <string>

#include "multilevel/mesh.h"

namespace pms::bench {

// Writes multilevel-figN-NAME.png into `dir` for `mesh` (built from edge collapses) and returns the report's
// lines: each picture with what its panels are.
std::string multilevel_figures(const std::filesystem::path& dir, const std::string& name, const MultilevelMesh& mesh);

}  // namespace pms::bench
