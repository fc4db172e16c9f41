// How the HTTP clients (receiver-driven, multilevel) reach a server: GETs pipelined on one connection,
// answered in request order (RFC 9112 §9.3.2). Their event handling takes answers in and gives targets out
// over this interface; the native build hands in HttpConnection (Boost.Beast, http_connection.h), the
// browser one over fetch, the tests one that calls the server's routes in process.
// Shared with the browser build: no asio, no threads (docs/architecture.md, "Layers").
#pragma once
#include <chrono>
#include <cstdint>
#include <functional>
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
  // The address the native connection sends from ("127.0.0.7"; empty: the system's choice): a test's
  // viewers on loopback, each its own client address to a server behind a proxy.
  std::string local_address;
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

// A target is a path under the server's prefix ("/models/m/VERSION/base"). At most room() GETs are pending (handed
// over, answer not fully arrived); a lost connection is a ConnectionError (client/transport.h).
class HttpTransport {
 public:
  virtual ~HttpTransport() = default;

  // Never waits (a free-running frame): post() hands a GET over; poll() makes the progress the transport
  // can make at once; take() gives the answers fully arrived, one a call, in request order.
  virtual void post(const std::string& target) = 0;
  virtual void poll() = 0;
  virtual std::optional<HttpAnswer> take() = 0;
  // Blocks until an answer can be taken, under the transport's deadlines: for lock-step and settling only
  // (a transport that cannot block, the browser's, throws).
  virtual void wait() = 0;
  virtual size_t pending() const = 0;
  virtual size_t room() const = 0;
  virtual const HttpCounters& counters() const = 0;

  // Lock-step: send() hands a GET over and starts it on its way, receive() waits for the answer to the
  // oldest one. By default post() + poll() and wait() until take() gives it; HttpConnection has a
  // synchronous path of its own.
  virtual void send(const std::string& target);
  virtual HttpAnswer receive();

  // GETs every target, up to room() at once, and hands each answer to `on_answer` in target order as it
  // arrives; nothing else may be pending.
  using OnAnswer = std::function<void(size_t index, HttpAnswer&& answer)>;
  void get_all(const std::vector<std::string>& targets, const OnAnswer& on_answer);
  std::vector<HttpAnswer> get_all(const std::vector<std::string>& targets);  // the answers, in target order
  HttpAnswer get(const std::string& target);
};

// GETs for a client that must not wait (the browser's event-driven open): posted as the transport has room,
// their answers collected as they arrive, in target order. Nothing else may be pending on the transport.
class PendingGets {
 public:
  explicit PendingGets(std::vector<std::string> targets);
  // Posts what fits, takes what has arrived, without waiting; true once every answer is in.
  bool advance(HttpTransport& http);
  const std::vector<std::string>& targets() const { return targets_; }
  std::vector<HttpAnswer>& answers() { return answers_; }

 private:
  std::vector<std::string> targets_;
  std::vector<HttpAnswer> answers_;
  size_t posted_ = 0, answered_ = 0;
};

}  // namespace pms::client
