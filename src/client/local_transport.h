// An in-process transport: the same frames as over TCP, to a server endpoint in the same process and
// without sockets, so a bench can read the server session's own state frame by frame. The endpoint is
// given as two calls, so this layer needs no server code (apps binds a server::Session to it).
#pragma once
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <vector>

#include "client/transport.h"
#include "protocol/framing.h"
#include "protocol/message_types.h"

namespace pms::client {

struct LocalEndpoint {
  std::function<void(protocol::Frame frame)> receive;  // a whole frame from the client
  // The next frame the server has to send, working for it as needed; nullptr when it has nothing to say.
  std::function<std::shared_ptr<const std::vector<uint8_t>>()> next_frame;
};

class LocalTransport : public Transport {
 public:
  explicit LocalTransport(LocalEndpoint endpoint, uint32_t max_client_message = protocol::kDefaultMaxMessage,
                          uint32_t max_server_message = protocol::kDefaultMaxMessage);

  void send(const std::vector<uint8_t>& frame) override;
  // The server's next frame; std::nullopt when it has nothing to say (no waiting here).
  std::optional<protocol::Frame> receive(std::chrono::milliseconds timeout) override;
  LinkCounters counters() const override { return counters_; }

 private:
  LocalEndpoint endpoint_;
  protocol::FrameReader to_server_, to_client_;
  LinkCounters counters_;
};

}  // namespace pms::client
