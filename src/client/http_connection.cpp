// The HTTP clients' native transport (http_connection.h), in the shape of Beast's client examples
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

namespace {

using Parser = http::response_parser<http::vector_body<uint8_t>>;

bool closed_by_peer(const error_code& ec) {
  return ec == http::error::end_of_stream || ec == asio::error::eof || ec == asio::error::connection_reset ||
         ec == asio::error::broken_pipe;
}

double ms_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

struct HttpConnection::Impl {
  Impl(const HttpUrl& u, const HttpOptions& o, HttpCounters& c) : url(u), options(o), counters(c) {}

  HttpUrl url;
  HttpOptions options;
  HttpCounters& counters;
  asio::io_context io;
  std::optional<beast::tcp_stream> stream;
  beast::flat_buffer buffer;
  std::deque<std::string> pending;  // GETs sent (or to send again on a new connection) and not yet answered
  std::deque<std::chrono::steady_clock::time_point> sent_at;  // when each of `pending` was handed over (post: written)
  size_t written = 0;                                         // of `pending`, those written on this connection
  bool fresh = false;  // no answer yet on this connection: a close now is the server's answer, not an idle close

  // The free-running side: at most one write and one read outstanding, each with its message kept here
  // until its handler has run (a cancelled operation still completes, later).
  std::optional<tcp::resolver> resolver;
  http::request<http::empty_body> request;  // being written
  std::optional<Parser> parser;             // being read
  bool connecting = false, writing = false, reading = false;
  bool closing = false;            // the stream is being closed: replaced once both operations have completed
  std::deque<HttpAnswer> arrived;  // answers read and not yet taken
  std::string failure;             // a lost connection, for the next poll() or wait() to throw

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

  http::request<http::empty_body> get_request(const std::string& target) const {
    http::request<http::empty_body> r{http::verb::get, url.prefix + target, 11};
    r.set(http::field::host, url.host + ":" + std::to_string(url.port));
    r.set(http::field::user_agent, "pmstream");
    r.keep_alive(true);
    return r;
  }

  void limit(Parser& p) const {
    p.header_limit(options.max_header);
    p.body_limit(options.max_body);
  }

  // The answer `p` has read, counted; the oldest pending GET's.
  HttpAnswer answer_of(Parser& p) const {
    HttpAnswer answer;
    answer.status = int(p.get().result_int());
    answer.body = std::move(p.get().body());
    if (const auto status = p.get().find("X-Cache-Status"); status != p.get().end())
      answer.cache_status = std::string(status->value().substr(0, 32));
    answer.sent_at = sent_at.front();
    counters.payload_down += answer.body.size();
    counters.last_answer_ms = ms_since(answer.sent_at);
    return answer;
  }

  // Every endpoint in turn; from options.local_address, the first one only (connecting to several reopens
  // the socket, which would drop the bound address).
  template <class Handler>
  void async_connect(const tcp::resolver::results_type& endpoints, Handler handler) {
    if (options.local_address.empty() || endpoints.empty())
      return stream->async_connect(endpoints, [handler](const error_code& e, const tcp::endpoint&) { handler(e); });
    error_code ec;
    const tcp::endpoint to = endpoints.begin()->endpoint();
    const asio::ip::address from = asio::ip::make_address(options.local_address, ec);
    tcp::socket& socket = stream->socket();
    if (!ec) socket.open(to.protocol(), ec);
    if (!ec) socket.bind({from, 0}, ec);
    if (ec) return asio::post(io, [handler, ec] { handler(ec); });
    stream->async_connect(to, handler);
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
    async_connect(endpoints, [&](const error_code& e) { ec = e; });
    run();
    if (ec) lost("cannot connect: " + reason(ec, options.connect_timeout));
  }

  // False when the write failed: the caller decides whether a closed kept-alive connection explains it.
  bool write(const std::string& target, error_code& ec) {
    const http::request<http::empty_body> r = get_request(target);
    size_t sent = 0;
    stream->expires_after(options.io_timeout);
    http::async_write(*stream, r, [&](const error_code& e, size_t n) {
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
  std::optional<HttpAnswer> read(bool& keep_alive, error_code& ec) {
    Parser p;
    limit(p);
    size_t received = 0;
    stream->expires_after(options.io_timeout);
    http::async_read(*stream, buffer, p, [&](const error_code& e, size_t n) {
      ec = e;
      received = n;
    });
    run();
    counters.bytes_down += received;
    if (ec) return std::nullopt;
    keep_alive = p.get().keep_alive();
    return answer_of(p);
  }

  bool async_busy() const { return connecting || writing || reading || closing || !arrived.empty(); }

  // The free-running side's one step: whatever can start now does (a connect, the next write, the next
  // read); each handler calls it again. Writes run ahead of reads up to the pending GETs, as send() does.
  void pump() {
    if (!failure.empty() || connecting) return;
    if (closing) {
      if (writing || reading) return;
      stream.reset();
      closing = false;
      written = 0;  // what was not answered goes again on the next connection
    }
    if (!stream) {
      if (!pending.empty()) start_connect();
      return;
    }
    if (!writing && written < pending.size()) start_write();
    if (!reading && written > 0) start_read();
  }

  void start_connect() {
    connecting = true;
    resolver.emplace(io);
    resolver->async_resolve(
        url.host, std::to_string(url.port), [this](const error_code& ec, tcp::resolver::results_type endpoints) {
          if (ec) return fail_async("cannot resolve the host: " + ec.message());
          stream.emplace(io);
          buffer.clear();
          stream->expires_after(options.connect_timeout);
          async_connect(endpoints, [this](const error_code& e) { on_connect(e); });
        });
  }

  void on_connect(const error_code& ec) {
    connecting = false;
    if (ec) return fail_async("cannot connect: " + reason(ec, options.connect_timeout));
    ++counters.connections;
    written = 0;
    fresh = true;
    pump();
  }

  void start_write() {
    writing = true;
    request = get_request(pending[written]);
    stream->expires_after(options.io_timeout);
    http::async_write(*stream, request, [this](const error_code& ec, size_t n) { on_write(ec, n); });
  }

  void on_write(const error_code& ec, size_t n) {
    writing = false;
    counters.bytes_up += n;
    if (closing || !failure.empty()) return pump();
    if (ec) return dropped(ec, pending[written]);
    ++counters.requests;
    sent_at[written++] = std::chrono::steady_clock::now();
    pump();
  }

  void start_read() {
    reading = true;
    limit(parser.emplace());
    stream->expires_after(options.io_timeout);
    http::async_read(*stream, buffer, *parser, [this](const error_code& ec, size_t n) { on_read(ec, n); });
  }

  void on_read(const error_code& ec, size_t n) {
    reading = false;
    counters.bytes_down += n;
    if (closing || !failure.empty()) return pump();
    if (ec) return dropped(ec, pending.front());
    fresh = false;
    arrived.push_back(answer_of(*parser));
    pending.pop_front();
    sent_at.pop_front();
    --written;
    if (!parser->get().keep_alive()) return close_and_pump();
    pump();
  }

  // A kept-alive connection the server closed is replaced and its unanswered GETs sent again; a fresh
  // one that fails, or any other error, loses the connection.
  void dropped(const error_code& ec, const std::string& target) {
    if (!fresh && closed_by_peer(ec)) return close_and_pump();
    fail_async(reason(ec, options.io_timeout) + " (" + target + ")");
  }

  void close_and_pump() {
    closing = true;
    stream->close();
    pump();
  }

  void fail_async(const std::string& what) {
    connecting = false;
    failure = origin() + ": " + what;
    pending.clear();
    sent_at.clear();
    if (stream) close_and_pump();
  }

  void rethrow() {
    if (failure.empty()) return;
    const std::string what = std::move(failure);
    failure.clear();
    throw ConnectionError(what);
  }
};

HttpConnection::HttpConnection(const HttpUrl& url, const HttpOptions& options)
    : impl_(std::make_unique<Impl>(url, options, counters_)) {
  if (options.in_flight == 0) fail("http", "in_flight must be at least 1");
}

HttpConnection::~HttpConnection() = default;

void HttpConnection::send(const std::string& target) {
  Impl& c = *impl_;
  if (c.async_busy()) fail("http", "send() while post()'s work is outstanding");
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
    if (!c.write(c.pending[c.written], ec)) {
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
  if (c.async_busy()) fail("http", "receive() while post()'s work is outstanding");
  for (;;) {
    flush();
    if (!c.stream) continue;
    error_code ec;
    bool keep_alive = false;
    std::optional<HttpAnswer> answer = c.read(keep_alive, ec);
    if (!answer) {
      if (!c.fresh && closed_by_peer(ec)) {
        c.stream.reset();  // a kept-alive connection the server closed: again on a new one
        continue;
      }
      c.lost(c.reason(ec, c.options.io_timeout) + " (" + c.pending.front() + ")");
    }
    c.fresh = false;
    c.sent_at.pop_front();
    c.pending.pop_front();
    --c.written;
    if (!keep_alive) c.stream.reset();
    return std::move(*answer);
  }
}

size_t HttpConnection::pending() const { return impl_->pending.size(); }
size_t HttpConnection::room() const { return impl_->options.in_flight - impl_->pending.size(); }

void HttpConnection::post(const std::string& target) {
  Impl& c = *impl_;
  if (c.pending.size() >= c.options.in_flight) fail("http", "more than in_flight GETs pending");
  c.pending.push_back(target);
  c.sent_at.push_back(std::chrono::steady_clock::now());
  c.pump();
}

void HttpConnection::poll() {
  Impl& c = *impl_;
  c.io.restart();
  c.io.poll();
  c.rethrow();
}

std::optional<HttpAnswer> HttpConnection::take() {
  Impl& c = *impl_;
  if (c.arrived.empty()) return std::nullopt;
  HttpAnswer answer = std::move(c.arrived.front());
  c.arrived.pop_front();
  return answer;
}

// One handler at a time until an answer is in: each outstanding operation ends by its deadline at the latest.
void HttpConnection::wait() {
  Impl& c = *impl_;
  while (c.arrived.empty()) {
    c.rethrow();
    if (c.pending.empty()) fail("http", "wait() with no GET pending");
    c.pump();
    c.io.restart();
    if (c.io.run_one() == 0) fail("http", "wait() with nothing in motion");
  }
}

}  // namespace pms::client
