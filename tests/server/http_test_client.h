// Test-only: a blocking HTTP/1.1 client on Boost.Beast over one loopback connection, for the HTTP
// transport's tests (keep-alive: every request goes over the same connection until it closes).
#pragma once
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace pms::test {

struct HttpReply {
  int status = 0;
  std::map<std::string, std::string> headers;  // names in lower case
  std::vector<uint8_t> body;
  std::string header(const std::string& name) const {
    const auto it = headers.find(name);
    return it == headers.end() ? std::string() : it->second;
  }
  std::string text() const { return {body.begin(), body.end()}; }
};

class HttpTestClient {
 public:
  // Reads wait at most timeout_ms. `from`: the loopback address to connect from (127.0.0.0/8 is all the
  // machine's), so tests can be several clients; `receive_buffer` > 0: SO_RCVBUF, set before connecting.
  explicit HttpTestClient(uint16_t port, int timeout_ms = 5000, const std::string& from = "127.0.0.1",
                          int receive_buffer = 0);
  ~HttpTestClient();

  HttpReply get(const std::string& target, const std::map<std::string, std::string>& headers = {});
  HttpReply head(const std::string& target);
  HttpReply post(const std::string& target, const std::vector<uint8_t>& body);
  // Sends `bytes` as they are, then reads one response.
  HttpReply raw(const std::string& bytes);
  void send(const std::string& bytes);  // without reading
  HttpReply read();
  // True when the server closes the connection within timeout_ms (reads return end of stream or reset).
  bool closed_by_server();
  // The bytes the server sends after the responses read so far, up to its close; nothing when it does not
  // close within timeout_ms of its last byte.
  std::optional<std::string> rest_until_closed();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace pms::test
