// The view-independent mode on the client, the baseline of kim-lee-kobbelt 2005 §8 (Fig. 9): splits come in
// PM order without refinement info and are applied as they arrive. qrefine never runs here, so the client
// sends VIEW every frame (it cannot know what it lacks) and the server decides how much of the PM order
// the view needs.
#pragma once
#include "client/client_mode.h"

namespace pms::client {

class ViewIndependentClient : public ClientMode {
 public:
  protocol::StreamMode wire_mode() const override { return protocol::StreamMode::view_independent; }
  void prepare(ClientSession& session) const override { session.refinement_info = false; }
  void frame(const Camera& camera, ClientSession& session, ViewRequests& server, FrameReport& report) override;
  // Every split as it arrives, in lock-step and free-running alike.
  void on_batch(const protocol::VSplits& batch, ClientSession& session) override;
  void settle(ClientSession&) override {}
};

}  // namespace pms::client
