// The client's WebSocket transport: link_core.h over Beast's websocket stream. Each frame goes out as one
// binary message; what comes in is read as a stream of frames, so the FrameReader bounds and checks it as
// it does over TCP.
#include "client/websocket_link.h"

#include <boost/beast/websocket.hpp>

#include "client/link_core.h"
#include "protocol/url_segment.h"

namespace pms::client {

namespace websocket = boost::beast::websocket;
using WebSocketStream = websocket::stream<boost::asio::ip::tcp::socket>;

namespace link_core {

template <>
struct StreamOps<WebSocketStream> {
  static tcp::socket& socket(WebSocketStream& s) { return s.next_layer(); }
  template <class Done>
  static void handshake(WebSocketStream& s, const std::string& host_port, const std::string& path,
                        uint32_t max_message, Done done) {
    s.binary(true);
    s.auto_fragment(false);
    s.read_message_max(uint64_t(max_message) + protocol::kFrameHeaderBytes);
    s.async_handshake(host_port, path, std::move(done));
  }
  // The rest of the frame as the message's final (only) piece.
  template <class Buffer, class Done>
  static void write_some(WebSocketStream& s, const Buffer& buffer, Done done) {
    s.async_write_some(true, buffer, std::move(done));
  }
  static bool closed_by_peer(const error_code& ec) {
    return ec == websocket::error::closed || ec == asio::error::eof;
  }
};

}  // namespace link_core

WebSocketLink::WebSocketLink(const std::string& host, uint16_t port, const std::string& path,
                             const LinkOptions& options)
    : Link(std::make_unique<link_core::LinkCore<WebSocketStream>>(options), host, port, path,
           "ws://" + host + ":" + std::to_string(port) + path) {}

std::optional<WebSocketUrl> parse_websocket_url(const std::string& text) {
  constexpr std::string_view kScheme = "ws://";
  if (!text.starts_with(kScheme)) return std::nullopt;
  const std::string_view rest = std::string_view(text).substr(kScheme.size());
  const size_t slash = std::min(rest.find('/'), rest.size());
  const std::string_view authority = rest.substr(0, slash);
  const size_t colon = authority.rfind(':');
  if (colon == std::string_view::npos || colon == 0) return std::nullopt;
  const std::optional<uint16_t> port = protocol::parse_port(authority.substr(colon + 1));
  if (!port) return std::nullopt;
  WebSocketUrl url{std::string(authority.substr(0, colon)), *port, std::string(rest.substr(slash))};
  if (url.path.empty()) url.path = "/ws";
  return url;
}

}  // namespace pms::client
