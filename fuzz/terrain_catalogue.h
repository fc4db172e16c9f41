// The model every server-side fuzz target serves: a small terrain built once, written to a scratch .pms and
// opened as a catalogue (the server reads models from files only), the scratch removed again.
#pragma once
#include <unistd.h>

#include <filesystem>
#include <memory>
#include <string>

#include "builder/build.h"
#include "io/shapes.h"
#include "server/catalogue.h"
#include "spm/pms_file.h"

namespace fuzz_model {

// `tag` names the scratch directory, so that fuzz targets running side by side do not share one.
inline std::shared_ptr<const pms::server::Catalogue> terrain_catalogue(const std::string& tag) {
  const pms::BuildResult built = pms::build_progressive_mesh(pms::make_terrain(2000), pms::BuildOptions{});
  const auto dir = std::filesystem::temp_directory_path() / ("pmstream-fuzz-" + tag + "-" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "terrain.pms").string();
  pms::write_pms(path, built.hierarchy, built.stats);
  auto catalogue = pms::server::Catalogue::open({path});
  std::filesystem::remove_all(dir);
  return catalogue;
}

}  // namespace fuzz_model
