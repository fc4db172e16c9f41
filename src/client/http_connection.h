// The receiver-driven client's HTTP/1.1 transport on Boost.Beast: one keep-alive connection with several
// GETs pipelined on it (answers come in request order, RFC 9112 §9.3.2), every connect, write and read under
// a deadline, every answer bounded, and bytes counted on the wire (headers included) and as payload apart.
// Two ways to drive it: synchronously (each call runs the connection's io_context until its work is done),
// or without ever waiting (post / poll / take: the free-running viewer's frame).
#pragma once
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace pms::client {

struct HttpOptions {
  std::chrono::milliseconds connect_timeout{5000};
  std::chrono::milliseconds io_timeout{30000};  // each write, and each answer from its first byte to its last
  uint32_t in_flight = 4;                       // GETs sent ahead of the answer being read
  uint64_t max_body = 64u << 20;
  uint32_t max_header = 16u << 10;
};

struct HttpCounters {
  uint64_t requests = 0;
  uint64_t bytes_up = 0, bytes_down = 0;  // on the wire: request and status lines, headers, bodies
  uint64_t payload_down = 0;              // the bodies of the answers alone
  uint64_t connections = 0;
  double last_answer_ms =
      0;  // the latest answer's latency: its GET handed to send() (or written) to its last byte read
};

struct HttpAnswer {
  int status = 0;
  std::vector<uint8_t> body;
  std::string cache_status;  // X-Cache-Status of a caching proxy in between (nginx: HIT, MISS, ...); else empty
  std::chrono::steady_clock::time_point sent_at;  // its GET handed to send(), or written for post()
};

// "http://HOST[:PORT][/prefix]": where a receiver-driven client finds the server's routes.
struct HttpUrl {
  std::string host;
  uint16_t port = 80;
  std::string prefix;  // without a trailing '/', empty for the root
};
// Throws pms::Error naming `where` for anything else (another scheme, a bad port, a query).
HttpUrl parse_http_url(const std::string& text, const std::string& where = "--server");

class HttpConnection {
 public:
  HttpConnection(const HttpUrl& url, const HttpOptions& options = {});
  ~HttpConnection();
  HttpConnection(const HttpConnection&) = delete;
  HttpConnection& operator=(const HttpConnection&) = delete;

  // GETs every target (under the URL's prefix), up to options.in_flight at once on the connection, and
  // hands each answer to `on_answer` in target order as it arrives. Connects on first use and again after
  // a server that closes a kept-alive connection (the requests it did not answer are sent again).
  // Throws ConnectionError for a failed connect, a deadline passed, a reset, or an answer over its limits.
  using OnAnswer = std::function<void(size_t index, HttpAnswer&& answer)>;
  void get_all(const std::vector<std::string>& targets, const OnAnswer& on_answer);
  HttpAnswer get(const std::string& target);

  // The same pipeline by hand, for a caller that keeps GETs in flight between calls (the receiver-driven
  // client's frame budget): send() writes a GET now, connecting first if need be, and at most
  // options.in_flight may be pending; receive() reads the answer to the oldest pending one, with the same
  // reconnect and deadlines as get_all. HTTP/1.1 cannot take a GET back once written: only closing the
  // connection would, so what is sent is read.
  void send(const std::string& target);
  HttpAnswer receive();
  size_t pending() const;
  size_t room() const;  // GETs send() or post() may still hand over: options.in_flight - pending()

  // The same pipeline for a caller that must never wait (the free-running viewer's frame): post() hands a
  // GET over and returns, connecting in the background if need be; poll() makes the progress the socket
  // allows at once (asio's poll: connect, writes, reads) and take() gives the answers fully arrived, in
  // request order. wait() blocks (under the deadlines) until one has arrived, for a caller that settles.
  // The same limits, deadlines and reconnect as send()/receive(); a lost connection is thrown by the next
  // poll() or wait(). The blocking calls refuse to run while this side has work outstanding.
  void post(const std::string& target);
  void poll();
  std::optional<HttpAnswer> take();
  void wait();

  const HttpCounters& counters() const { return counters_; }

 private:
  void flush();
  struct Impl;
  std::unique_ptr<Impl> impl_;
  HttpCounters counters_;
};

}  // namespace pms::client
