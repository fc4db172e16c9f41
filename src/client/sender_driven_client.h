// The sender-driven mode on the client (kim-lee-kobbelt 2005 §5.3): the client refines on its own with the
// hierarchy it holds and sends VIEW only when its front needs vsplit packets it does not have.
#pragma once
#include "client/client_mode.h"

namespace pms::client {

class SenderDrivenClient : public ClientMode {
 public:
  protocol::StreamMode wire_mode() const override { return protocol::StreamMode::sender_driven; }
  void prepare(ClientSession& session) const override { session.refinement_info = true; }
  void frame(const Camera& camera, ClientSession& session, ViewRequests& server, FrameReport& report) override;
  void settle(ClientSession& session) override;
};

}  // namespace pms::client
