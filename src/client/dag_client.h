// The DAG mode on the client (zheng-chan 2006, StreamMode::dag): a thin client with no criteria and no
// hierarchy walk of its own. Each frame sends DAG_VIEW (the view, N, the traversal, FREE or BUDGET and its
// budget) and applies the DAG_OPS that answer it as they come: collapses, then splits, each legal on this
// mesh when it comes. Its mesh is the server's cut of the DAG after every frame.
// Shared with the browser build: single-threaded, no std::ranges algorithms, std::format or coroutines.
#pragma once
#include "client/client_mode.h"

namespace pms::client {

class DagClient : public ClientMode {
 public:
  protocol::StreamMode wire_mode() const override { return protocol::StreamMode::dag; }
  void prepare(ClientSession& session) const override { session.refinement_info = false; }
  // The vertices of the mesh, not the leaves held: they name the server's cut (records of collapsed nodes
  // stay in the hierarchy, their splits come again in full).
  std::vector<VertexId> resume_front(const ClientSession& session) const override { return session.mesh_vertices(); }
  void frame(const Camera& camera, ClientSession& session, ViewRequests& server, FrameReport& report) override;
  void settle(ClientSession&) override {}

  // Free-running: DAG_OPS are applied as they arrive (free_running_session.cpp). An answer with operations
  // was N-limited management (zheng-chan §5), so at a camera that stays, the next DAG_VIEW goes on where it
  // stopped, as the next frame of lock-step does; one without operations is the traversal's fixed point.
  uint32_t rounds_per_view() const override { return kRounds; }
  bool answers_are_capped() const override { return true; }
  std::vector<uint8_t> encode_request(const protocol::DagView& request) const override {
    return protocol::encode(request);
  }

 private:
  // A bound on a traversal that never settles (a budget it keeps trading faces under), not a target.
  static constexpr uint32_t kRounds = 64;
};

}  // namespace pms::client
