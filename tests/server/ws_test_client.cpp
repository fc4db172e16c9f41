// The Beast WebSocket test client (ws_test_client.h).
#include "ws_test_client.h"

#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket.hpp>

#include "http_test_client.h"
#include "loopback_socket.h"
#include "protocol/framing.h"
#include "protocol/server_messages.h"

namespace pms::test {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace websocket = beast::websocket;
using asio::ip::tcp;

struct WsTestClient::Impl {
  asio::io_context io;
  websocket::stream<tcp::socket> ws{io};
  beast::flat_buffer buffer;
};

WsTestClient::WsTestClient(uint16_t port, const std::string& origin, const std::string& from, int timeout_ms,
                           int receive_buffer)
    : impl_(std::make_unique<Impl>()) {
  connect_loopback(impl_->ws.next_layer(), port, from, timeout_ms, receive_buffer);
  impl_->ws.set_option(websocket::stream_base::decorator([origin](websocket::request_type& request) {
    if (!origin.empty()) request.set(beast::http::field::origin, origin);
  }));
  impl_->ws.binary(true);
  impl_->ws.handshake("127.0.0.1:" + std::to_string(port), "/ws");
}

WsTestClient::~WsTestClient() = default;

void WsTestClient::send_binary(const std::vector<uint8_t>& bytes) {
  impl_->ws.binary(true);
  impl_->ws.write(asio::buffer(bytes));
}

void WsTestClient::send_text(const std::string& text) {
  impl_->ws.text(true);
  impl_->ws.write(asio::buffer(text));
}

bool WsTestClient::send_raw(const std::vector<uint8_t>& bytes) {
  boost::system::error_code ec;
  asio::write(impl_->ws.next_layer(), asio::buffer(bytes), ec);
  return !ec;
}

std::optional<std::vector<uint8_t>> WsTestClient::read() {
  boost::system::error_code ec;
  impl_->buffer.clear();
  impl_->ws.read(impl_->buffer, ec);
  if (ec) return std::nullopt;
  const auto data = impl_->buffer.data();
  const auto* bytes = static_cast<const uint8_t*>(data.data());
  return std::vector<uint8_t>(bytes, bytes + data.size());
}

bool WsTestClient::closed_by_server(std::optional<protocol::ErrorCode>* error) {
  for (;;) {
    boost::system::error_code ec;
    impl_->buffer.clear();
    impl_->ws.read(impl_->buffer, ec);
    if (ec == asio::error::would_block || ec == asio::error::try_again || ec == asio::error::timed_out) return false;
    if (ec) return true;
    const auto data = impl_->buffer.data();
    protocol::FrameReader reader;
    reader.feed(static_cast<const uint8_t*>(data.data()), data.size());
    protocol::Frame frame;
    if (error && reader.next(frame) && frame.type == protocol::MessageType::error)
      *error = protocol::decode_error(frame.payload).code;
  }
}

std::vector<uint8_t> ws_frame(uint8_t opcode, bool fin, const std::vector<uint8_t>& payload) {
  std::vector<uint8_t> frame{uint8_t((fin ? 0x80 : 0) | opcode)};
  const size_t n = payload.size();
  if (n < 126) {
    frame.push_back(uint8_t(0x80 | n));
  } else if (n < 65536) {
    frame.insert(frame.end(), {uint8_t(0x80 | 126), uint8_t(n >> 8), uint8_t(n)});
  } else {
    frame.push_back(uint8_t(0x80 | 127));
    for (int shift = 56; shift >= 0; shift -= 8) frame.push_back(uint8_t(uint64_t(n) >> shift));
  }
  const uint8_t mask[4] = {0x12, 0x34, 0x56, 0x78};
  frame.insert(frame.end(), mask, mask + 4);
  for (size_t i = 0; i < n; ++i) frame.push_back(payload[i] ^ mask[i % 4]);
  return frame;
}

int upgrade_status(uint16_t port, const std::map<std::string, std::string>& extra, const std::string& from) {
  std::map<std::string, std::string> headers{{"Host", "127.0.0.1:" + std::to_string(port)},
                                             {"Upgrade", "websocket"},
                                             {"Connection", "Upgrade"},
                                             {"Sec-WebSocket-Key", "dGhlIHNhbXBsZSBub25jZQ=="},
                                             {"Sec-WebSocket-Version", "13"}};
  for (const auto& [name, value] : extra) headers[name] = value;
  std::string request = "GET /ws HTTP/1.1\r\n";
  for (const auto& [name, value] : headers)
    if (!value.empty()) request += name + ": " + value + "\r\n";
  HttpTestClient client(port, 5000, from);
  return client.raw(request + "\r\n").status;
}

}  // namespace pms::test
