// The one place a client's streaming modes are chosen: a new mode adds its case here and its own files.
#include "client/client_mode.h"

#include "client/dag_client.h"
#include "client/sender_driven_client.h"
#include "client/sender_plain_client.h"
#include "client/view_independent_client.h"
#include "common/error.h"

namespace pms::client {

std::unique_ptr<ClientMode> make_client_mode(protocol::StreamMode mode) {
  switch (mode) {
    case protocol::StreamMode::sender_driven:
      return std::make_unique<SenderDrivenClient>();
    case protocol::StreamMode::view_independent:
      return std::make_unique<ViewIndependentClient>();
    case protocol::StreamMode::sender_plain:
      return std::make_unique<SenderPlainClient>();
    case protocol::StreamMode::dag:
      return std::make_unique<DagClient>();
  }
  fail("client", "a streaming mode this client does not know");
}

protocol::Open open_request(const std::string& model, const ClientMode& mode, const ClientSession& session) {
  protocol::Open message{model, {}, mode.wire_mode()};
  if (session.has_model()) message.resume = mode.resume_front(session);
  return message;
}

}  // namespace pms::client
