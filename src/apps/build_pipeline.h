// load -> clean -> build -> write: the path shared by `build`, `demo` and the bench.
#pragma once
#include <nlohmann/json.hpp>
#include <string>

#include "apps/build_memory.h"
#include "builder/build.h"
#include "io/mesh.h"
#include "spm/pms_file.h"

namespace pms::app {

struct BuildRun {
  BuildStats stats;
  CleanReport clean;
  double load_seconds = 0;
  double clean_seconds = 0;
  double build_seconds = 0;  // simplification, hierarchy, cut vertices, refinement info
  double write_seconds = 0;
  uint64_t output_bytes = 0;
  bool texcoords_dropped = false;  // the input had texture coordinates, which .pms does not carry
};

std::string describe(const CleanReport& report);

// Builds an already loaded mesh (cleaned here) and writes OUT.pms.
BuildRun build_mesh(Mesh mesh, const std::string& input_name, const std::string& out_path, const BuildOptions& options);
// A mesh file (any supported format, .gz/.xz), or "terrain:FACES" for the built-in terrain
// ("terrain:FACES:colors": with land colours).
Mesh load_input(const std::string& in_path, const ProgressFn& progress);
// Loads IN (see load_input) then as above, with the builder's memory tuning on until it returns.
BuildRun build_file(const std::string& in_path, const std::string& out_path, const BuildOptions& options,
                    AfterBuild after = AfterBuild::kExit);

// The `build --json` object (docs/cli.md, "build").
nlohmann::json build_json(const BuildRun& run, double seconds, double peak_rss_mb);
nlohmann::json stats_json(const BuildStats& stats);

}  // namespace pms::app
