#include "client/sender_plain_client.h"

namespace pms::client {

void SenderPlainClient::frame(const Camera& camera, ClientSession& session, ViewRequests& server, FrameReport& report) {
  report.vsplits = server.request_view(
      camera, [this, &session](const protocol::VSplits& batch) { on_batch(batch, session); }, report);
}

void SenderPlainClient::on_batch(const protocol::VSplits& batch, ClientSession& session) {
  // v_s and the cut vertices a packet names are active neighbours on this mesh when it comes (the
  // server's order); SelectiveMesh refuses cut vertices that are not.
  session.apply_as_they_come(batch, "the packet's cut vertices are not this mesh's");
}

}  // namespace pms::client
