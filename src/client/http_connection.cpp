// The receiver-driven client's HTTP transport (http_connection.h), in the shape of Beast's client examples
// with tcp_stream's timeouts: each step is one asynchronous operation run to completion on the
// connection's own io_context, so a deadline passed is an error like any other.
#include <utility>  // before asio with C++20 (docs/architecture.md, "Stack")

#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <deque>
#include <optional>

#include "client/http_connection.h"
#include "client/transport.h"
#include "common/error.h"

namespace pms::client {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
using asio::ip::tcp;
using boost::system::error_code;

HttpUrl parse_http_url(const std::string& text, const std::string& where) {
  const std::string scheme = "http://";
  if (text.compare(0, scheme.size(), scheme) != 0) fail(where, "'" + text + "' is not http://HOST[:PORT][/prefix]");
  HttpUrl url;
  const std::string rest = text.substr(scheme.size());
  const size_t slash = rest.find('/');
  const std::string authority = rest.substr(0, slash);
  if (slash != std::string::npos) url.prefix = rest.substr(slash);
  while (!url.prefix.empty() && url.prefix.back() == '/') url.prefix.pop_back();
  if (url.prefix.find_first_of("?#") != std::string::npos) fail(where, "'" + text + "': no query or fragment");
  const size_t colon = authority.rfind(':');
  url.host = authority.substr(0, colon);
  if (url.host.empty()) fail(where, "'" + text + "' names no host");
  if (colon != std::string::npos) {
    const std::string port = authority.substr(colon + 1);
    unsigned long value = 0;
    try {
      size_t used = 0;
      value = std::stoul(port, &used);
      if (used != port.size()) value = 0;
    } catch (const std::exception&) {
      value = 0;
    }
    if (value == 0 || value > 65535) fail(where, "'" + text + "' has no valid port");
    url.port = uint16_t(value);
  }
  return url;
}

struct HttpConnection::Impl {
  Impl(const HttpUrl& u, const HttpOptions& o) : url(u), options(o) {}

  HttpUrl url;
  HttpOptions options;
  asio::io_context io;
  std::optional<beast::tcp_stream> stream;
  beast::flat_buffer buffer;
  std::deque<std::string> pending;  // GETs sent (or to send again on a new connection) and not yet answered
  std::deque<std::chrono::steady_clock::time_point> sent_at;  // when each of `pending` was first handed over
  size_t written = 0;                                         // of `pending`, those written on this connection
  bool fresh = false;  // no answer yet on this connection: a close now is the server's answer, not an idle close

  std::string origin() const { return "http://" + url.host + ":" + std::to_string(url.port); }

  void run() {
    io.restart();
    io.run();
  }

  [[noreturn]] void lost(const std::string& what) {
    stream.reset();
    pending.clear();
    sent_at.clear();
    written = 0;
    throw ConnectionError(origin() + ": " + what);
  }

  std::string reason(const error_code& ec, std::chrono::milliseconds deadline) const {
    if (ec == beast::error::timeout) return "no progress within " + std::to_string(deadline.count()) + " ms";
    if (ec == http::error::partial_message) return "the server closed the connection mid-answer";
    if (ec == http::error::body_limit) return "an answer over " + std::to_string(options.max_body) + " bytes";
    if (ec == http::error::header_limit) return "answer headers over " + std::to_string(options.max_header) + " bytes";
    return ec.message();
  }

  void connect() {
    stream.emplace(io);
    buffer.clear();
    error_code ec;
    tcp::resolver::results_type endpoints;
    tcp::resolver resolver(io);
    resolver.async_resolve(url.host, std::to_string(url.port), [&](const error_code& e, tcp::resolver::results_type r) {
      ec = e;
      endpoints = std::move(r);
    });
    run();
    if (ec) lost("cannot resolve the host: " + ec.message());
    stream->expires_after(options.connect_timeout);
    stream->async_connect(endpoints, [&](const error_code& e, const tcp::endpoint&) { ec = e; });
    run();
    if (ec) lost("cannot connect: " + reason(ec, options.connect_timeout));
  }

  // False when the write failed: the caller decides whether a closed kept-alive connection explains it.
  bool write(const std::string& target, HttpCounters& counters, error_code& ec) {
    http::request<http::empty_body> request{http::verb::get, url.prefix + target, 11};
    request.set(http::field::host, url.host + ":" + std::to_string(url.port));
    request.set(http::field::user_agent, "pmstream");
    request.keep_alive(true);
    size_t sent = 0;
    stream->expires_after(options.io_timeout);
    http::async_write(*stream, request, [&](const error_code& e, size_t n) {
      ec = e;
      sent = n;
    });
    run();
    counters.bytes_up += sent;
    if (ec) return false;
    ++counters.requests;
    return true;
  }

  // Nothing (and `closed`) when the server closed the connection before the answer's first byte.
  std::optional<HttpAnswer> read(HttpCounters& counters, bool& keep_alive, error_code& ec) {
    http::response_parser<http::vector_body<uint8_t>> parser;
    parser.header_limit(options.max_header);
    parser.body_limit(options.max_body);
    size_t received = 0;
    stream->expires_after(options.io_timeout);
    http::async_read(*stream, buffer, parser, [&](const error_code& e, size_t n) {
      ec = e;
      received = n;
    });
    run();
    counters.bytes_down += received;
    if (ec) return std::nullopt;
    HttpAnswer answer;
    answer.status = int(parser.get().result_int());
    answer.body = std::move(parser.get().body());
    if (const auto status = parser.get().find("X-Cache-Status"); status != parser.get().end())
      answer.cache_status = std::string(status->value().substr(0, 32));
    counters.payload_down += answer.body.size();
    keep_alive = parser.get().keep_alive();
    return answer;
  }
};

HttpConnection::HttpConnection(const HttpUrl& url, const HttpOptions& options)
    : impl_(std::make_unique<Impl>(url, options)) {
  if (options.in_flight == 0) fail("http", "in_flight must be at least 1");
}

HttpConnection::~HttpConnection() = default;

namespace {

bool closed_by_peer(const error_code& ec) {
  return ec == http::error::end_of_stream || ec == asio::error::eof || ec == asio::error::connection_reset ||
         ec == asio::error::broken_pipe;
}

}  // namespace

void HttpConnection::send(const std::string& target) {
  Impl& c = *impl_;
  if (c.pending.size() >= c.options.in_flight) fail("http", "more than in_flight GETs pending");
  c.pending.push_back(target);
  c.sent_at.push_back(std::chrono::steady_clock::now());
  flush();
}

// Writes what is pending and not yet written, on a new connection if there is none. A kept-alive
// connection the server closed is dropped, for receive() to send again on a new one.
void HttpConnection::flush() {
  Impl& c = *impl_;
  if (!c.stream) {
    c.connect();
    ++counters_.connections;
    c.written = 0;
    c.fresh = true;
  }
  while (c.written < c.pending.size()) {
    error_code ec;
    if (!c.write(c.pending[c.written], counters_, ec)) {
      if (!c.fresh && closed_by_peer(ec)) {
        c.stream.reset();
        return;
      }
      c.lost(c.reason(ec, c.options.io_timeout) + " (" + c.pending[c.written] + ")");
    }
    ++c.written;
  }
}

// At most two passes an answer: a closed kept-alive connection is replaced by a fresh one, and a fresh
// one that fails is an error.
HttpAnswer HttpConnection::receive() {
  Impl& c = *impl_;
  if (c.pending.empty()) fail("http", "receive() with no GET pending");
  for (;;) {
    flush();
    if (!c.stream) continue;
    error_code ec;
    bool keep_alive = false;
    std::optional<HttpAnswer> answer = c.read(counters_, keep_alive, ec);
    if (!answer) {
      if (!c.fresh && closed_by_peer(ec)) {
        c.stream.reset();  // a kept-alive connection the server closed: again on a new one
        continue;
      }
      c.lost(c.reason(ec, c.options.io_timeout) + " (" + c.pending.front() + ")");
    }
    c.fresh = false;
    counters_.last_answer_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - c.sent_at.front()).count();
    c.sent_at.pop_front();
    c.pending.pop_front();
    --c.written;
    if (!keep_alive) c.stream.reset();
    return std::move(*answer);
  }
}

size_t HttpConnection::pending() const { return impl_->pending.size(); }
size_t HttpConnection::room() const { return impl_->options.in_flight - impl_->pending.size(); }

void HttpConnection::get_all(const std::vector<std::string>& targets, const OnAnswer& on_answer) {
  if (pending() != 0) fail("http", "get_all() with GETs of another caller pending");
  size_t sent = 0;
  for (size_t answered = 0; answered < targets.size(); ++answered) {
    while (sent < targets.size() && room() > 0) send(targets[sent++]);
    on_answer(answered, receive());
  }
}

HttpAnswer HttpConnection::get(const std::string& target) {
  HttpAnswer out;
  get_all({target}, [&](size_t, HttpAnswer&& answer) { out = std::move(answer); });
  return out;
}

}  // namespace pms::client
