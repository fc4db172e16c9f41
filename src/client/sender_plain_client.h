// kim-lee-kobbelt 2005 §6.3's variation on the client (StreamMode::sender_plain, Fig. 10 middle column): a
// viewer that will not refine on its own. The server picks the splits for each view from the client's
// front, as in the sender-driven mode, but each packet names the cut vertices the split has on this
// client's mesh and carries no refinement info. The client applies every split as it arrives and never
// coarsens, so its front is the server's; with no qrefine of its own it sends VIEW every frame.
// Shared with the browser build: single-threaded, no std::ranges algorithms, std::format or coroutines.
#pragma once
#include "client/client_mode.h"

namespace pms::client {

class SenderPlainClient : public ClientMode {
 public:
  protocol::StreamMode wire_mode() const override { return protocol::StreamMode::sender_plain; }
  void prepare(ClientSession& session) const override { session.refinement_info = false; }
  void frame(const Camera& camera, ClientSession& session, ViewRequests& server, FrameReport& report) override;
  // Every split as it arrives, in lock-step and free-running alike.
  void on_batch(const protocol::VSplits& batch, ClientSession& session) override;
  void settle(ClientSession&) override {}
};

}  // namespace pms::client
