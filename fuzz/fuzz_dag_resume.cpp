// libFuzzer target for a DAG session's resume: the input is the front code of an OPEN with the DAG
// and resume bits (the first byte picks the tree count the OPEN announces: the model's, or another), sent to a
// real Session serving a real model. The session must end with a peer's ERROR (never internal) or resume with
// a cut that passes DagCut::check, within bounded work per pump; a resumed session then answers a DAG_VIEW.
// Small slices (64 leaves) so the front is decoded over several pumps.
#include <unistd.h>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "dag/compact.h"
#include "protocol/client_messages.h"
#include "protocol/framing.h"
#include "protocol/message_types.h"
#include "server/catalogue.h"
#include "server/dag_mode.h"
#include "server/limits.h"
#include "server/session.h"
#include "terrain_catalogue.h"

namespace pms::fuzz {
namespace {

struct Served {
  std::shared_ptr<const server::Catalogue> catalogue;
  server::ServerLimits limits;
};

const Served& served() {
  static const Served s = [] {
    Served out;
    out.limits.slice_work = 64;
    out.limits.batch_splits = 16;
    out.catalogue = fuzz_model::terrain_catalogue("dag-resume");
    return out;
  }();
  return s;
}

protocol::Frame frame_of(const std::vector<uint8_t>& bytes) {
  protocol::Frame frame;
  frame.type = protocol::MessageType(bytes[4]);
  frame.payload.assign(bytes.begin() + protocol::kFrameHeaderBytes, bytes.end());
  return frame;
}

void check(bool ok, const std::string& what) {
  if (ok) return;
  std::fprintf(stderr, "fuzz_dag_resume: %s\n", what.c_str());
  std::abort();
}

}  // namespace
}  // namespace pms::fuzz

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace pms;
  using namespace pms::fuzz;
  if (size == 0) return 0;
  const Served& s = served();
  const server::ServedModel& model = *s.catalogue->find("terrain");
  const uint32_t roots = model.model().root_count;
  // OPEN{terrain, DAG} with the resume bit set, a tree count and the input as the front's code.
  protocol::Frame open = frame_of(protocol::encode(protocol::Open{"terrain", {}, protocol::StreamMode::dag}));
  open.payload.back() |= 1;  // flags, the payload's last byte: a resume front follows
  const uint32_t trees = data[0] < 240 ? roots : roots + data[0] - 247;
  for (int k = 0; k < 4; ++k) open.payload.push_back(uint8_t(trees >> (8 * k)));
  open.payload.insert(open.payload.end(), data + 1, data + size);

  server::Session session(s.catalogue, s.limits);
  session.receive(frame_of(protocol::encode(protocol::Hello{protocol::kProtocolVersion, "fuzz"})));
  session.receive(std::move(open));
  // A slice of leaves, at most 63 split bits above each, and the load of the cut at the end.
  const uint64_t work_bound = 64 * s.limits.slice_work + 2 * uint64_t(model.tables->dag().size());
  for (int pumps = 0; session.pump(); ++pumps) {
    check(pumps < 100000, "the resume does not end");
    check(session.last_work() <= work_bound, "a pump did " + std::to_string(session.last_work()) + " units");
  }
  check(session.error() != protocol::ErrorCode::internal, "internal error: " + session.error_text());
  if (session.error()) return 0;
  const auto& mode = dynamic_cast<const server::DagSessionMode&>(*session.session_mode());
  check(mode.opened(), "neither resumed nor refused");
  std::string why;
  check(mode.cut().dense(model.tables->dag()).check(&why), "the resumed cut: " + why);
  check(mode.state_bytes() < sizeof(server::DagSessionMode) + model.tables->dag().size() / 4 + 64,
        "the state after a resume");
  protocol::DagView view;
  view.view.frame = 1;
  session.receive(frame_of(protocol::encode(view)));
  for (int pumps = 0; session.pump(); ++pumps) check(pumps < 100000, "the answer does not end");
  check(!session.error(), "a DAG_VIEW after a resume: " + session.error_text());
  check(mode.cut().dense(model.tables->dag()).check(&why), "the cut after a DAG_VIEW: " + why);
  return 0;
}
