// A shared model as the server benches use it: built into a .pms by a child `pmstream build` (so the
// build's memory is not this process's), then opened the way `serve` opens it.
#pragma once
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "apps/camera_path.h"
#include "bench/bench.h"
#include "client/local_transport.h"
#include "server/catalogue.h"
#include "server/session.h"

namespace pms::bench {

struct BenchModel {
  std::string name;  // the model's short name, "-bound" appended for --deviation bound
  std::filesystem::path pms;
  std::shared_ptr<const server::Catalogue> catalogue;
  const server::ServedModel* served = nullptr;
};

// `deviation` as `pmstream build --deviation` takes it. A .pms an earlier group of this run built is
// reused (the temp dir lives as long as the run).
BenchModel prepare_model(const BenchContext& context, const std::string& model,
                         const std::string& deviation = "estimate");

std::vector<Camera> path_of(const BenchModel& m, app::PathKind kind, uint32_t frames);

// The calling thread's CPU time: a share of a flight that the machine's other load does not inflate.
double thread_seconds();

// A server Session of the model's catalogue in this process, and a client transport to it: the same
// frames as over TCP, with the session's own state (its active tags) readable between frames.
struct InProcessSession {
  std::shared_ptr<server::Session> session;
  std::unique_ptr<client::LocalTransport> transport;
  // The thread CPU time the session's receive() and pump() took: the server's share of a flight.
  std::shared_ptr<double> server_seconds;
};
// The calling thread's CPU time in seconds: an in-process session's work, and its client's, without the
// time the thread waited for a core.
double thread_seconds();

InProcessSession in_process_session(const BenchModel& m, const server::ServerLimits& limits = {});

}  // namespace pms::bench
