// The client's transport over the HTTP server's WebSocket (ws://HOST:PORT/ws): the session modes through
// anything that passes HTTP, each binary message one frame of the TCP protocol (docs/protocol.md,
// "WebSocket"), under the same deadlines and bounds as the TCP Link.
#pragma once
#include <cstdint>
#include <optional>
#include <string>

#include "client/link.h"

namespace pms::client {

// A Link whose stream is a WebSocket: the same queues, deadlines and counters (bytes of the frames, not of
// the WebSocket's own headers).
class WebSocketLink : public Link {
 public:
  // Connects to host:port and upgrades GET `path`; ConnectionError when either fails in connect_timeout.
  WebSocketLink(const std::string& host, uint16_t port, const std::string& path, const LinkOptions& options = {});
};

// A ws://HOST:PORT[/path] URL's parts (path "/ws" when none is given); nothing for other text.
struct WebSocketUrl {
  std::string host;
  uint16_t port = 0;
  std::string path;
};
std::optional<WebSocketUrl> parse_websocket_url(const std::string& text);

}  // namespace pms::client
