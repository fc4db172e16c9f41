// A shared model as the server benches use it: built into a .pms by a child `pmstream build` (so the
// build's memory is not this process's), then opened the way `serve` opens it.
#pragma once
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "apps/bench/bench.h"
#include "apps/camera_path.h"
#include "server/server.h"

namespace pms::app {

struct BenchModel {
  std::string name;  // the model's short name, "-bound" appended for --deviation bound
  std::filesystem::path pms;
  std::shared_ptr<const server::Catalogue> catalogue;
  const server::ServedModel* served = nullptr;
};

// `deviation` as `pmstream build --deviation` takes it. A .pms an earlier group of this run built is
// reused (the temp dir lives as long as the run).
BenchModel prepare_model(const BenchContext& context, const std::string& model, const std::string& deviation = "estimate");

std::vector<Camera> path_of(const BenchModel& m, PathKind kind, uint32_t frames);

}  // namespace pms::app
