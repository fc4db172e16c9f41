#include "apps/bench/bench_model.h"

#include <cstdio>

#include "apps/bench/child_process.h"
#include "common/error.h"

namespace pms::app {
namespace fs = std::filesystem;

BenchModel prepare_model(const BenchContext& context, const std::string& model, const std::string& deviation) {
  const std::string name = deviation == "estimate" ? model : model + "-" + deviation;
  BenchModel m;
  m.name = name;
  m.pms = context.temp_dir / (name + ".pms");
  if (!fs::exists(m.pms)) {
    std::fprintf(stderr, "bench: building %s ... ", name.c_str());
    const ChildResult run = run_child({context.self_exe, "build", find_model(context.models_dir, model).string(), "-o",
                                       m.pms.string(), "--deviation", deviation, "--json"});
    if (!run.ok()) fail(name, "pmstream build: " + run.failure());
    std::fprintf(stderr, "%.2f s\n", run.wall_seconds);
  }
  m.catalogue = server::Catalogue::open({m.pms.string()});
  m.served = m.catalogue->find(name);
  return m;
}

std::vector<Camera> path_of(const BenchModel& m, PathKind kind, uint32_t frames) {
  PathOptions options;
  options.frames = frames;
  return make_camera_path(kind, m.served->view(), options);
}

}  // namespace pms::app
