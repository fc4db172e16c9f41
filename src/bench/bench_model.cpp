#include "bench/bench_model.h"

#include <time.h>

#include <cstdio>
#include <deque>
#include <utility>

#include "bench/child_process.h"
#include "common/error.h"
#include "server/catalogue.h"
#include "server/limits.h"
#include "server/session.h"

namespace pms::bench {
using app::make_camera_path;
using app::PathKind;
using app::PathOptions;
namespace fs = std::filesystem;

BenchModel prepare_model(const BenchContext& context, const std::string& model, const std::string& deviation) {
  const std::string name = deviation == "estimate" ? model : model + "-" + deviation;
  BenchModel m;
  m.name = name;
  m.pms = context.temp_dir / (name + ".pms");
  if (!fs::exists(m.pms)) {
    std::fprintf(stderr, "bench: building %s ... ", name.c_str());
    const ChildResult run = run_child({context.pmstream_exe, "build", find_model(context.models_dir, model).string(),
                                       "-o", m.pms.string(), "--deviation", deviation, "--json"});
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
  return make_camera_path(kind, m.served->model(), options);
}

double thread_seconds() {
  timespec now{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
  return double(now.tv_sec) + 1e-9 * double(now.tv_nsec);
}

InProcessSession in_process_session(const BenchModel& m, const server::ServerLimits& limits) {
  auto session = std::make_shared<server::Session>(m.catalogue, limits);
  auto seconds = std::make_shared<double>(0);
  client::LocalEndpoint endpoint;
  endpoint.receive = [session, seconds](protocol::Frame frame) {
    const double start = thread_seconds();
    session->receive(std::move(frame));
    *seconds += thread_seconds() - start;
  };
  endpoint.next_frame = [session, seconds]() -> server::Buffer {
    std::deque<server::Buffer>& outbox = session->outbox();
    while (outbox.empty()) {
      const double start = thread_seconds();
      const bool more = session->pump();
      *seconds += thread_seconds() - start;
      if (!more) return nullptr;
    }
    server::Buffer frame = std::move(outbox.front());
    outbox.pop_front();
    return frame;
  };
  return {session, std::make_unique<client::LocalTransport>(std::move(endpoint), limits.max_client_message), seconds};
}

}  // namespace pms::bench
