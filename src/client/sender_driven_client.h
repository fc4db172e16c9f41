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

  // Free-running: batches are only attached; adapt() says whether qrefine misses packets.
  bool adapt(const Camera& camera, ClientSession& session) override;
  bool asks_every_view() const override { return false; }
  uint32_t rounds_per_view() const override { return kRounds; }

 private:
  // The server answers a VIEW with every split the view wants over its front, so one request per view
  // normally suffices; more only if an answer was cut short.
  static constexpr uint32_t kRounds = 4;
};

}  // namespace pms::client
