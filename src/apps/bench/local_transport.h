// An in-process pipe between a StreamingClient and a server Session: the same frames as over TCP,
// without sockets, so the bench can read a session's own state (its active-tag window) frame by frame.
#pragma once
#include <deque>
#include <memory>

#include "client/client.h"
#include "server/server.h"

namespace pms::app {

class LocalTransport : public client::Transport {
 public:
  LocalTransport(std::shared_ptr<const server::Catalogue> catalogue, const server::ServerLimits& limits = {});

  void send(const std::vector<uint8_t>& frame) override;
  // Pumps the session for its next frame; std::nullopt when it has nothing to say (no waiting here).
  std::optional<protocol::Frame> receive(std::chrono::milliseconds timeout) override;
  client::LinkCounters counters() const override { return counters_; }

  // The server's side of this connection (stays valid while the transport lives).
  const server::Session& session() const { return *session_; }

 private:
  std::shared_ptr<server::Session> session_;
  protocol::FrameReader to_server_, to_client_;
  client::LinkCounters counters_;
};

}  // namespace pms::app
