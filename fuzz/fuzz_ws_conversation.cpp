// libFuzzer target for the WebSocket on the HTTP port (docs/protocol.md, "WebSocket"): the real HttpServer
// on loopback, with short deadlines, a small message bound and a low message rate, gets an upgrade request
// (a valid one, or one with the input's headers) and then WebSocket frames composed from the input: binary,
// text, continuation, ping, pong, close and reserved opcodes, fin set or not, masked or not, carrying the
// protocol's real messages (HELLO, LIST, OPEN in each mode, CLOSE) or the input's bytes. What comes back must
// be one HTTP answer the upgrade documents and, after a 101, unmasked server frames whose binary messages
// each hold exactly one protocol frame; the server must end the conversation within its deadlines.
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <utility>  // before asio with C++20 (docs/architecture.md, "Stack")

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "conversation.h"
#include "protocol/client_messages.h"
#include "protocol/framing.h"
#include "server/catalogue.h"
#include "server/http_server.h"
#include "server/limits.h"
#include "terrain_catalogue.h"

namespace {

using namespace pms;
using namespace pms::server;
using fuzz_conversation::Chunks;
using fuzz_conversation::Clock;
using fuzz_conversation::converse;

void check(bool condition) {
  if (!condition) __builtin_trap();
}

HttpServer& fuzzed_server() {
  static HttpServer* const started = [] {
    auto catalogue = fuzz_model::terrain_catalogue("ws");
    HttpLimits limits;
    limits.idle_timeout_ms = 300;
    limits.request_timeout_ms = 200;
    limits.write_timeout_ms = 300;
    limits.threads = 2;
    WebOptions web;
    web.sessions.handshake_timeout_ms = 300;
    web.sessions.frame_timeout_ms = 200;
    web.sessions.idle_timeout_ms = 500;
    web.sessions.write_timeout_ms = 300;
    web.sessions.max_client_message = 4096;
    web.sessions.max_message_rate = 50;
    web.sessions.turn_us = 50;
    web.sessions.slice_work = 64;
    auto* server = new HttpServer(std::move(catalogue), limits, "127.0.0.1", 0, web);  // lives as long as the process
    server->start();
    return server;
  }();
  return *started;
}

struct Script {
  std::string_view bytes;
  uint8_t next() {
    if (bytes.empty()) return 0;
    const uint8_t b = uint8_t(bytes.front());
    bytes.remove_prefix(1);
    return b;
  }
  std::vector<uint8_t> take(size_t n) {
    const std::string_view taken = bytes.substr(0, n);
    bytes.remove_prefix(taken.size());
    return {taken.begin(), taken.end()};
  }
};

std::string upgrade(Script& script, uint16_t port) {
  const uint8_t form = script.next();
  std::string request = "GET /ws HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(port) + "\r\n";
  if (form % 8 != 1) request += "Upgrade: websocket\r\nConnection: Upgrade\r\n";
  if (form % 8 != 2) request += "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n";
  request += form % 8 == 3 ? "Sec-WebSocket-Version: 8\r\n" : "Sec-WebSocket-Version: 13\r\n";
  if (form % 8 == 4) request += "Origin: http://elsewhere.example\r\n";
  if (form % 8 == 5) request += "Origin: http://127.0.0.1:" + std::to_string(port) + "\r\n";
  return request + "\r\n";
}

std::vector<uint8_t> message(Script& script) {
  switch (script.next() % 8) {
    case 0: return protocol::encode(protocol::Hello{protocol::kProtocolVersion, "fuzz"});
    case 1: return protocol::encode(protocol::List{});
    case 2: return protocol::encode(protocol::Open{"terrain", {}, protocol::StreamMode(script.next() % 4)});
    case 3: return protocol::encode(protocol::Close{});
    default: return script.take(script.next() % 64);
  }
}

// One client frame (RFC 6455 §5.2) from the script.
void frame(Script& script, std::string& out) {
  const uint8_t form = script.next();
  static constexpr uint8_t kOpcodes[] = {2, 2, 2, 0, 1, 9, 10, 8, 3, 11};
  const uint8_t opcode = kOpcodes[form % 10];
  const bool fin = (form & 0x10) == 0;
  const bool masked = (form & 0x60) != 0x60;
  const std::vector<uint8_t> payload = message(script);
  out += char((fin ? 0x80 : 0) | opcode);
  const size_t n = payload.size();
  out += char((masked ? 0x80 : 0) | (n < 126 ? n : 126));
  if (n >= 126) {
    out += char(n >> 8);
    out += char(n & 0xFF);
  }
  const uint8_t mask[4] = {script.next(), script.next(), script.next(), script.next()};
  if (masked) out.append(reinterpret_cast<const char*>(mask), 4);
  for (size_t i = 0; i < n; ++i) out += char(masked ? payload[i] ^ mask[i % 4] : payload[i]);
}

// The answer's status line, then after a 101 the server's frames: unmasked, and each binary message one
// whole protocol frame. A reset may cut the last one.
void check_received(std::string_view received) {
  if (received.empty()) return;  // reset before the answer went out (the request deadline)
  check(received.starts_with("HTTP/1.1 "));
  const int status = std::atoi(std::string(received.substr(9, 3)).c_str());
  check(status == 101 || status == 400 || status == 403 || status == 426 || status == 503);
  if (status != 101) return;
  const size_t end = received.find("\r\n\r\n");
  check(end != std::string_view::npos);
  std::string_view frames = received.substr(end + 4);
  while (frames.size() >= 2) {
    const uint8_t b0 = uint8_t(frames[0]), b1 = uint8_t(frames[1]);
    check((b1 & 0x80) == 0);  // a server never masks
    size_t length = b1 & 0x7F, header = 2;
    if (length == 126) {
      if (frames.size() < 4) return;
      length = size_t(uint8_t(frames[2])) << 8 | uint8_t(frames[3]);
      header = 4;
    } else if (length == 127) {
      if (frames.size() < 10) return;
      length = 0;
      for (int i = 2; i < 10; ++i) length = length << 8 | uint8_t(frames[size_t(i)]);
      header = 10;
    }
    if (frames.size() < header + length) return;
    if ((b0 & 0x0F) == 2) {
      check((b0 & 0x80) != 0);  // never fragmented
      protocol::FrameReader reader(protocol::kDefaultMaxMessage);
      reader.feed(reinterpret_cast<const uint8_t*>(frames.data() + header), length);
      protocol::Frame one;
      check(reader.next(one) && reader.ready() == 0 && !reader.mid_frame());
    }
    frames.remove_prefix(header + length);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 3) return 0;
  const uint16_t port = fuzzed_server().port();
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  check(fd >= 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(port);
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  check(::connect(fd, reinterpret_cast<const sockaddr*>(&address), sizeof address) == 0);
  Script script{std::string_view(reinterpret_cast<const char*>(data + 2), size - 2)};
  std::string conversation = upgrade(script, port);
  while (!script.bytes.empty() && conversation.size() < 65536) frame(script, conversation);
  std::string received;
  // The server's longest wait: a session's handshake, frame or write deadline, then its close's.
  const bool ended = converse(fd, conversation, Chunks{uint32_t(data[0]) << 8 | data[1]}, received,
                              Clock::now() + std::chrono::seconds(4));
  ::close(fd);
  check(ended);
  check_received(received);
  return 0;
}
