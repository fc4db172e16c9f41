// libFuzzer target for whole HTTP conversations (docs/architecture.md, "Correctness properties", 5): the
// real HttpServer on loopback, with short deadlines, a tiny turn and a small budget so that slicing,
// pauses and deadlines all happen, gets a conversation over one connection in the chunks the input
// chooses, pipelined as they come, then the end of the stream. Input byte 0 picks the form: the rest as
// raw bytes, or as a script of requests composed from the server's resources and framing cases (valid
// split codes, HEADs, chunked bodies, Expect, smuggling attempts, raw noise), so that the fuzzer reaches
// long pipelines of real requests without having to invent them. What comes back must be a sequence of
// well-formed HTTP responses with a status the server documents, and the server must end the connection
// within its deadlines: nothing may crash, hang or leave the conversation half-answered. The per-request
// target (fuzz_http_request) reaches the routes faster; this one reaches the connection's state machine.
#include <fcntl.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <utility>  // before asio with C++20 (docs/architecture.md, "Stack")

#include <boost/asio.hpp>
#include <boost/beast/http.hpp>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "protocol/base64url.h"
#include "protocol/split_request.h"
#include "server/catalogue.h"
#include "server/http_server.h"
#include "server/limits.h"
#include "conversation.h"
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

struct Served {
  HttpServer* http = nullptr;
  uint32_t root_count = 0;
};

const Served& fuzzed_server() {
  static const Served served = [] {
    auto catalogue = fuzz_model::terrain_catalogue("conv");
    HttpLimits limits;
    limits.max_request_ids = 64;
    limits.max_response_splits = 256;
    limits.idle_timeout_ms = 300;
    limits.request_timeout_ms = 200;
    limits.write_timeout_ms = 300;
    limits.turn_us = 20;
    limits.address_budget = 20000;
    limits.connection_budget = 10000;
    limits.threads = 2;
    const uint32_t roots = catalogue->find("terrain")->model().root_count;
    auto* started = new HttpServer(std::move(catalogue), limits, "127.0.0.1", 0);  // lives as long as the process
    started->start();
    return Served{started, roots};
  }();
  return served;
}

// Reads the script's bytes, zero past the end.
struct Script {
  std::string_view bytes;
  uint8_t next() {
    if (bytes.empty()) return 0;
    const uint8_t b = uint8_t(bytes.front());
    bytes.remove_prefix(1);
    return b;
  }
  std::string take(size_t n) {
    const std::string taken(bytes.substr(0, n));
    bytes.remove_prefix(taken.size());
    return taken;
  }
};

// A request code the routes decode: ids among the terrain's roots (and a few nodes below), a depth.
std::string split_code(Script& script) {
  protocol::SplitRequest request{uint32_t(script.next() % 4), {}};
  const size_t ids = 1 + script.next() % 40;
  for (size_t i = 0; i < ids; ++i) {
    const uint32_t tree = (uint32_t(script.next()) << 8 | script.next()) % fuzzed_server().root_count;
    request.ids.push_back(VertexId{tree, 1u + script.next() % 4});
  }
  return protocol::base64url_encode(protocol::encode_split_request(request));
}

std::string request_line(const char* method, const std::string& target) {
  return std::string(method) + " " + target + " HTTP/1.1\r\nHost: a\r\n";
}

// One request of the script, or noise.
std::string composed_request(Script& script) {
  const std::string code_url = "/models/terrain/splits/";
  switch (script.next() % 14) {
    case 0: return request_line("GET", "/models") + "\r\n";
    case 1: return request_line("GET", "/models/terrain/base") + "\r\n";
    case 2: return request_line("HEAD", "/models/terrain/base") + "\r\n";
    case 3: return request_line("GET", code_url + split_code(script)) + "\r\n";
    case 4: return request_line("HEAD", code_url + split_code(script)) + "\r\n";
    case 5: {
      const std::string body = script.take(script.next() % 64);
      return request_line("POST", "/models/terrain/splits") + "Content-Length: " + std::to_string(body.size()) +
             "\r\n\r\n" + body;
    }
    case 6: {
      const std::string body = script.take(script.next() % 64);
      return request_line("POST", "/models/terrain/splits") + "Transfer-Encoding: chunked\r\n\r\n" +
             (body.empty() ? "" : std::to_string(body.size()) + "\r\n" + body + "\r\n") + "0\r\n\r\n";
    }
    case 7: return request_line("GET", "/models/terrain/blocks/" + std::to_string(script.next()) + "/1/2") + "\r\n";
    case 8: return request_line("GET", "/models/terrain/codec") + "\r\n";
    case 9: return "GET /models HTTP/1.0\r\nConnection: keep-alive\r\n\r\n";
    case 10: return request_line("GET", "/models") + "Connection: close\r\n\r\n";
    case 11:
      return request_line("POST", "/models/terrain/splits") + "Transfer-Encoding: chunked, identity\r\n\r\n" +
             request_line("GET", "/models") + "\r\n";
    case 12:
      return request_line("POST", "/models/terrain/splits") + "Expect: 100-continue\r\nContent-Length: 4\r\n\r\n" +
             script.take(4);
    default: return script.take(script.next() % 32);
  }
}

std::string composed_conversation(std::string_view bytes) {
  Script script{bytes};
  std::string conversation;
  while (!script.bytes.empty() && conversation.size() < 65536) conversation += composed_request(script);
  return conversation;
}

// Every response in `received`: a documented status and whole headers, then its body, but for the last
// response, which a reset may cut. The answers to HEADs have no body although they give its length, and
// which requests were HEADs only the server's parse knows: a response followed at once by another
// status line had none.
void check_responses(std::string_view received) {
  namespace http = boost::beast::http;
  while (!received.empty()) {
    http::response_parser<http::empty_body> parser;
    parser.skip(true);
    boost::beast::error_code ec;
    const size_t used = parser.put(boost::asio::buffer(received.data(), received.size()), ec);
    if (ec == http::error::need_more) return;  // cut by a reset
    check(!ec && parser.is_header_done());
    const unsigned status = parser.get().result_int();
    check(status == 100 || status == 200 || status == 301 || status == 304 || (status >= 400 && status <= 431) ||
          status == 500 || status == 501 || status == 503);
    received.remove_prefix(used);
    const uint64_t length = parser.content_length().value_or(0);
    if (received.starts_with("HTTP/1.") || status == 100 || status == 304) continue;
    received.remove_prefix(std::min<uint64_t>(length, received.size()));
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 3) return 0;
  const uint16_t port = fuzzed_server().http->port();
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  check(fd >= 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(port);
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  check(::connect(fd, reinterpret_cast<const sockaddr*>(&address), sizeof address) == 0);
  std::string received;
  const std::string_view input(reinterpret_cast<const char*>(data + 3), size - 3);
  const std::string composed = data[2] % 2 ? composed_conversation(input) : std::string();
  const std::string_view bytes = data[2] % 2 ? std::string_view(composed) : input;
  // The server's longest wait is a paused connection's budget, then a deadline: well under two seconds.
  const bool ended = converse(fd, bytes, Chunks{uint32_t(data[0]) << 8 | data[1]}, received,
                              Clock::now() + std::chrono::seconds(3));
  ::close(fd);
  check(ended);
  check_responses(received);
  return 0;
}
