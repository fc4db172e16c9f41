// The HTTP transport on Boost.Beast (Beast's async server examples: one object per connection owning its
// stream, buffer and parser; shared_from_this at the connection boundary only). A connection holds no
// state between requests but its buffer: every answer comes from the routes over the catalogue.
// Deadlines (docs/operating.md, "HTTP"): idle_timeout_ms for the first byte of a request, then
// request_timeout_ms for the rest of it, and write_timeout_ms for each piece of the answer to be taken.
#include "server/http_server.h"

#include <utility>  // before asio with C++20 (docs/architecture.md, "Stack")
#include <boost/asio.hpp>

#include <atomic>
#include <cstdio>
#include <mutex>
#include <optional>
#include <sstream>
#include <thread>

#include "common/error.h"
#include "server/http_message.h"
#include "server/http_routes.h"
#include "server/io_threads.h"

namespace pms::server {
namespace {

namespace asio = boost::asio;
namespace beast = boost::beast;
using asio::ip::tcp;
using std::chrono::milliseconds;

void log_line(const std::string& line) { std::fprintf(stderr, "pmstream serve: http: %s\n", line.c_str()); }

class HttpConnection : public std::enable_shared_from_this<HttpConnection> {
 public:
  HttpConnection(tcp::socket socket, const Catalogue& catalogue, const HttpLimits& limits, HttpStats& stats)
      : stream_(std::move(socket)), catalogue_(catalogue), limits_(limits), stats_(stats) {}
  ~HttpConnection() { stats_.connections_active--; }

  void start() {
    boost::system::error_code ignored;
    stream_.socket().set_option(tcp::no_delay(true), ignored);
    read_request();
  }

 private:
  // The first bytes of a request under the idle deadline, the rest under the request deadline.
  void read_request() {
    parser_.emplace();
    bound_parser(*parser_, limits_);
    stream_.expires_after(milliseconds(limits_.idle_timeout_ms));
    http::async_read_some(stream_, buffer_, *parser_,
                          [self = shared_from_this()](beast::error_code ec, size_t n) { self->on_first_bytes(ec, n); });
  }

  void on_first_bytes(beast::error_code ec, size_t n) {
    stats_.bytes_in += n;
    if (ec || parser_->is_done()) return on_request(ec);
    stream_.expires_after(milliseconds(limits_.request_timeout_ms));
    http::async_read(stream_, buffer_, *parser_, [self = shared_from_this()](beast::error_code ec2, size_t n2) {
      self->stats_.bytes_in += n2;
      self->on_request(ec2);
    });
  }

  void on_request(beast::error_code ec) {
    if (ec == http::error::end_of_stream || ec == asio::error::eof || ec == asio::error::connection_reset)
      return close();
    if (ec == beast::error::timeout) {
      stats_.connections_timed_out++;
      return close();  // a peer that sends too slowly would not read an answer either
    }
    if (ec) {  // the parser refused the request: answer, then close (the stream is out of step)
      const auto data = buffer_.data();
      const std::string_view buffered(static_cast<const char*>(data.data()), data.size());
      return respond(parse_error_answer(ec, buffered), false, false, 11);
    }
    const auto& request = parser_->get();
    stats_.requests++;
    HttpAnswer answer;
    try {
      answer = answer_request(catalogue_, limits_, request);
    } catch (const std::exception& e) {  // out of memory for an answer: this request's fault only
      log_line(std::string("internal error: ") + e.what());
      answer = error_answer(500, "internal error");
    }
    respond(std::move(answer), request.method() == http::verb::head, request.keep_alive(), request.version());
  }

  void respond(HttpAnswer answer, bool head, bool keep_alive, unsigned version) {
    if (answer.status == 304) stats_.not_modified++;
    if (answer.status >= 400 && answer.status < 500) stats_.client_errors++;
    stats_.splits_served += answer.splits;
    stats_.split_requests += answer.split_resource;
    answer_ = std::move(answer);
    response_.emplace(make_response(answer_, head, keep_alive, version));
    serializer_.emplace(*response_);
    write_some();
  }

  // A piece at a time, each under the write deadline: a peer that takes nothing for that long is closed,
  // a slow one that keeps reading is not.
  void write_some() {
    stream_.expires_after(milliseconds(limits_.write_timeout_ms));
    http::async_write_some(stream_, *serializer_, [self = shared_from_this()](beast::error_code ec, size_t n) {
      self->on_written(ec, n);
    });
  }

  void on_written(beast::error_code ec, size_t n) {
    stats_.bytes_out += n;
    if (ec == beast::error::timeout) stats_.connections_timed_out++;
    if (ec) return close();
    if (!serializer_->is_done()) return write_some();
    const bool keep_alive = response_->keep_alive();
    serializer_.reset();
    response_.reset();
    answer_ = {};
    if (!keep_alive) return close();
    read_request();
  }

  void close() {
    boost::system::error_code ignored;
    stream_.socket().shutdown(tcp::socket::shutdown_send, ignored);
    stream_.close();
  }

  beast::tcp_stream stream_;
  beast::flat_buffer buffer_;
  std::optional<HttpParser> parser_;
  HttpAnswer answer_;
  std::optional<HttpResponse> response_;  // its body is a span into answer_
  std::optional<http::response_serializer<http::span_body<const uint8_t>>> serializer_;
  const Catalogue& catalogue_;
  const HttpLimits& limits_;
  HttpStats& stats_;
};

// The answer to a connection over the limit, written once without waiting: it fits any socket buffer.
void refuse(tcp::socket& socket) {
  static const std::string text = [] {
    // The response's body is a span into the answer, which must outlive the serialization.
    const HttpAnswer answer = error_answer(503, "the server is at its connection limit; try again later");
    HttpResponse response = make_response(answer, false, false, 11);
    std::ostringstream out;
    out << response;
    return out.str();
  }();
  boost::system::error_code ignored;
  socket.non_blocking(true, ignored);
  socket.write_some(asio::buffer(text), ignored);
  socket.shutdown(tcp::socket::shutdown_both, ignored);
  socket.close(ignored);
}

}  // namespace

struct HttpServer::Impl {
  Impl(std::shared_ptr<const Catalogue> c, const HttpLimits& l) : catalogue(std::move(c)), limits(l) {}

  void accept() {
    acceptor.async_accept(asio::make_strand(io), [this](const boost::system::error_code& ec, tcp::socket socket) {
      if (ec == asio::error::operation_aborted) return;  // stopped
      if (ec) return accept_failed(ec);
      admit(std::move(socket));
      accept();
    });
  }

  // Out of descriptors, accepting again at once would fail again at once.
  void accept_failed(const boost::system::error_code& ec) {
    log_line("accept: " + ec.message() + "; retrying in 100 ms");
    backoff.expires_after(milliseconds(100));
    backoff.async_wait([this](const boost::system::error_code& wait_ec) {
      if (!wait_ec) accept();
    });
  }

  void admit(tcp::socket socket) {
    if (stats.connections_active.load() >= limits.max_connections) {
      stats.connections_refused++;
      return refuse(socket);
    }
    try {
      stats.connections_active++;  // the connection's destructor takes it back
      stats.connections_opened++;
      std::make_shared<HttpConnection>(std::move(socket), *catalogue, limits, stats)->start();
    } catch (const std::exception& e) {
      log_line(std::string("accept: internal error: ") + e.what());
    }
  }

  std::shared_ptr<const Catalogue> catalogue;
  HttpLimits limits;
  HttpStats stats;
  std::vector<std::thread> threads;
  std::mutex stop_mutex;
  bool stopped = false;
  // Last: destroyed first, with the connections its handlers still hold (they use the members above).
  asio::io_context io;
  tcp::acceptor acceptor{io};
  asio::steady_timer backoff{io};
};

HttpServer::HttpServer(std::shared_ptr<const Catalogue> catalogue, const HttpLimits& limits, const std::string& host,
                       uint16_t port)
    : impl_(std::make_unique<Impl>(std::move(catalogue), limits)) {
  listen_on(impl_->acceptor, host, port, "HTTP");
}

HttpServer::~HttpServer() { stop(); }

uint16_t HttpServer::port() const { return impl_->acceptor.local_endpoint().port(); }

void HttpServer::start() {
  impl_->accept();
  start_io_threads(impl_->io, impl_->limits.threads, impl_->threads, log_line);
}

// Connections hold no state worth a goodbye: the loop stops, and destroying it closes their sockets.
void HttpServer::stop() {
  {
    std::lock_guard<std::mutex> lock(impl_->stop_mutex);
    if (impl_->stopped) return;
    impl_->stopped = true;
  }
  impl_->io.stop();
  for (std::thread& t : impl_->threads)
    if (t.joinable()) t.join();
}

const HttpStats& HttpServer::stats() const { return impl_->stats; }

}  // namespace pms::server
