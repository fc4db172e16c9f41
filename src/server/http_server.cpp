// The HTTP transport: Beast's request parser over a plain socket (asio's examples: one object per
// connection owning its socket, buffer and parser; shared_from_this at the connection boundary only). A
// connection holds no state between requests but its buffer: every answer comes from the routes over the
// catalogue. What a request costs the server is mostly system calls and wake-ups, not the routes
// (docs/internals.md, "The HTTP server"), so:
// - each I/O thread runs an io_context of its own and a connection lives on one of them: no strand, no
//   lock handed between threads, no other thread woken per request;
// - an answer is written at once with one gather write (headers, body) on the non-blocking socket, and
//   only a peer that does not take it all is waited for;
// - requests already buffered (pipelined) are parsed and answered without reading again;
// - one timer per connection holds its deadline, and is moved only when a deadline comes nearer.
// Deadlines (docs/operating.md, "HTTP"): idle_timeout_ms for the first byte of a request, then
// request_timeout_ms for the rest of it, and write_timeout_ms for each piece of the answer to be taken.
#include "server/http_server.h"

#include <utility>  // before asio with C++20 (docs/architecture.md, "Stack")

#include <boost/asio.hpp>

#include <array>
#include <atomic>
#include <cstdio>
#include <mutex>
#include <optional>
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
using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

// Bytes read at a time. With the parser's limits it bounds the buffer: a request is parsed before more is read.
constexpr size_t kReadChunk = 16384;
// Pipelined requests answered in one go before other connections of the thread get their turn.
constexpr int kAnswersPerTurn = 16;

void log_line(const std::string& line) { std::fprintf(stderr, "pmstream serve: http: %s\n", line.c_str()); }

// The one deadline a connection is under (idle, request or write). Pushing it later, as every answer does
// with the idle deadline, is a store; the timer moves only when the deadline comes nearer, and when it
// fires early it waits again for the rest.
class Deadline {
 public:
  explicit Deadline(const asio::any_io_executor& executor) : timer_(executor) {}

  // `on_expiry` runs once the deadline set last has passed, unless cancel() came first.
  template <class OnExpiry>
  void set(uint32_t ms, OnExpiry on_expiry) {
    at_ = Clock::now() + milliseconds(ms);
    if (!armed_ || timer_.expiry() > at_) arm(std::move(on_expiry));
  }
  void cancel() {
    ++generation_;
    armed_ = false;
    timer_.cancel();
  }

 private:
  template <class OnExpiry>
  void arm(OnExpiry on_expiry) {
    armed_ = true;
    timer_.expires_at(at_);
    timer_.async_wait([this, generation = ++generation_, on_expiry](const boost::system::error_code& ec) {
      if (ec || generation != generation_) return;  // moved or cancelled since
      if (Clock::now() < at_) return arm(on_expiry);
      armed_ = false;
      on_expiry();
    });
  }

  asio::steady_timer timer_;
  Clock::time_point at_{};
  uint64_t generation_ = 0;
  bool armed_ = false;
};

class HttpConnection : public std::enable_shared_from_this<HttpConnection> {
 public:
  HttpConnection(tcp::socket socket, const Catalogue& catalogue, const HttpLimits& limits, HttpStats& stats,
                 const void* server)
      : socket_(std::move(socket)),
        deadline_(socket_.get_executor()),
        buffer_(size_t(limits.max_header_bytes) + limits.max_body_bytes + kReadChunk),
        catalogue_(catalogue),
        limits_(limits),
        stats_(stats),
        server_(server) {}
  ~HttpConnection() {
    catalogue_.table_builds().forget_owner(this);
    stats_.connections_active--;
  }

  void start() {
    boost::system::error_code ignored;
    socket_.set_option(tcp::no_delay(true), ignored);
    socket_.non_blocking(true, ignored);
    set_deadline(limits_.idle_timeout_ms);
    serve();
  }

 private:
  void set_deadline(uint32_t ms) {
    deadline_.set(ms, [self = shared_from_this()] {
      if (self->waiting_) return self->stop_waiting();
      self->stats_.connections_timed_out++;  // a peer that sends too slowly would not read an answer either
      self->close();
    });
  }

  // Answers the whole requests in the buffer, then reads more, unless an answer is still being written.
  void serve() {
    for (int answered = 0; !closed_;) {
      if (writing_ || waiting_) return;
      if (answered == kAnswersPerTurn)
        return asio::post(socket_.get_executor(), [self = shared_from_this()] { self->serve(); });
      if (!parser_) {
        parser_.emplace();
        bound_parser(*parser_, limits_);
        parser_->eager(false);  // the header alone: accept_header sees it before any byte of a body is taken
      }
      beast::error_code ec;
      const size_t used = buffer_.size() ? parser_->put(buffer_.data(), ec) : 0;
      buffer_.consume(used);
      if (ec && ec != http::error::need_more) return refuse_request(ec);
      if (parser_->is_header_done() && !parser_->eager() && !accept_header()) return;
      if (parser_->is_done()) {
        answer();
        ++answered;
        continue;
      }
      if (used && buffer_.size()) continue;  // the header is in, the body goes on
      return read_more();
    }
  }

  // Under the idle deadline until a request's first bytes are in, then under the request deadline, set
  // once: a request that comes whole in one read (nearly all) is answered before it would matter.
  void read_more() {
    const bool begun = buffer_.size() || parser_->got_some();
    if (begun && !request_begun_) {
      request_begun_ = true;
      set_deadline(limits_.request_timeout_ms);
    }
    // Waiting for the bytes, then reading them: a read tried at once, just after an answer went out, finds
    // nothing and contends for the socket's lock with the peer's acknowledgement (perf, loopback).
    socket_.async_wait(tcp::socket::wait_read, [self = shared_from_this()](boost::system::error_code ec) {
      if (ec) return self->close();  // the deadline closed the socket
      self->read_now();
    });
  }

  void read_now() {
    const size_t room = std::min(kReadChunk, buffer_.max_size() - buffer_.size());
    if (room == 0) return refuse_request(http::error::header_limit);  // the parser's limits come first
    boost::system::error_code ec;
    const size_t n = socket_.read_some(buffer_.prepare(room), ec);
    buffer_.commit(n);
    stats_.bytes_in += n;
    if (ec == asio::error::would_block || ec == asio::error::try_again) return read_more();
    if (ec) return close();  // the peer left
    serve();
  }

  void answer() {
    stats_.requests++;
    route_request();
  }

  // The header is in, its body not yet read: a request the server refuses on its header is answered and
  // its connection closed before its body could be read as a next request; one whose client waits for
  // "100 Continue" gets it unless the body has begun to come anyway (RFC 9110 §10.1.1).
  bool accept_header() {
    if (std::optional<HeaderRefusal> refusal = refuse_header(*parser_)) {
      finish_request(std::move(refusal->answer), refusal->close);
      return false;
    }
    parser_->eager(true);
    if (expects_continue(*parser_) && buffer_.size() == 0) send_continue();
    return true;
  }

  void send_continue() {
    head_text_ = "HTTP/1.1 100 Continue\r\n\r\n";
    body_ = {};
    written_ = 0;
    writing_ = interim_ = true;
    write();
  }

  // The request in the parser, routed; one whose tables are being built waits for them (wait_for_tables).
  void route_request() {
    HttpAnswer answer;
    try {
      answer = answer_request(catalogue_, limits_, parser_->get());
    } catch (const std::exception& e) {  // out of memory for an answer: this request's fault only
      log_line(std::string("internal error: ") + e.what());
      answer = error_answer(500, "internal error");
    }
    if (answer.waits_for) return wait_for_tables(std::move(answer));
    finish_request(std::move(answer));
  }

  // One request at a time per connection, under the request deadline: the connection stops reading and
  // routes it again when a builder wakes it (on_tables_settled), or answers the 503 at the deadline.
  void wait_for_tables(HttpAnswer answer) {
    const asio::any_io_executor executor = socket_.get_executor();
    TableWaiter waiter{this, server_, [weak = weak_from_this(), executor] {
                         asio::post(executor, [weak] {
                           if (const auto self = weak.lock()) self->on_tables_settled();
                         });
                       }};
    if (catalogue_.table_builds().request(*answer.waits_for, answer.waits_for_mode, std::move(waiter)))
      return route_request();  // built meanwhile
    waiting_ = true;
    pending_answer_ = std::move(answer);
    set_deadline(limits_.request_timeout_ms);
  }

  void on_tables_settled() {
    if (closed_ || !waiting_) return;
    waiting_ = false;
    route_request();
    serve();
  }

  // The request deadline passed while its tables were being built: the 503 (Retry-After) goes out.
  void stop_waiting() {
    waiting_ = false;
    catalogue_.table_builds().forget_owner(this);
    finish_request(std::move(pending_answer_));
    serve();
  }

  void finish_request(HttpAnswer answer, bool close = false) {
    const auto& request = parser_->get();
    const bool head = request.method() == http::verb::head;
    const bool keep_alive = request.keep_alive() && !close;
    const unsigned version = request.version();
    parser_.reset();
    request_begun_ = false;
    respond(std::move(answer), head, keep_alive, version);
  }

  // The parser refused the request: answer, then close (the stream is out of step).
  void refuse_request(const beast::error_code& ec) {
    const auto data = buffer_.data();
    const std::string_view buffered(static_cast<const char*>(data.data()), data.size());
    respond(parse_error_answer(ec, *parser_, buffered, limits_), false, false, 11);
  }

  void respond(HttpAnswer answer, bool head, bool keep_alive, unsigned version) {
    if (answer.status == 304) stats_.not_modified++;
    if (answer.status >= 400 && answer.status < 500) stats_.client_errors++;
    stats_.splits_served += answer.splits;
    stats_.split_requests += answer.split_resource;
    answer_ = std::move(answer);
    write_response_head(answer_, keep_alive, version, head_text_);
    body_ = head || answer_.status == 304 ? std::span<const uint8_t>() : answer_.body();
    keep_alive_ = keep_alive;
    written_ = 0;
    writing_ = true;
    write();
  }

  // As much as the socket takes now; the rest when it can take more, each piece under the write deadline:
  // a peer that takes nothing for that long is closed, a slow one that keeps reading is not.
  void write() {
    const size_t total = head_text_.size() + body_.size();
    while (written_ < total) {
      boost::system::error_code ec;
      const size_t n = socket_.write_some(unwritten(), ec);
      written_ += n;
      stats_.bytes_out += n;
      if (ec == asio::error::would_block || ec == asio::error::try_again) {
        set_deadline(limits_.write_timeout_ms);
        socket_.async_wait(tcp::socket::wait_write, [self = shared_from_this()](boost::system::error_code wait_ec) {
          if (wait_ec) return self->close();
          self->write();
          if (!self->writing_) self->serve();
        });
        return;
      }
      if (ec) return close();
    }
    writing_ = false;
    if (std::exchange(interim_, false)) return;  // the 100 Continue: the body comes next, under its deadline
    answer_ = {};
    if (!keep_alive_) return close();
    set_deadline(limits_.idle_timeout_ms);
  }

  std::array<asio::const_buffer, 2> unwritten() const {
    const size_t head = head_text_.size();
    if (written_ >= head)
      return {asio::const_buffer(), asio::buffer(body_.data() + (written_ - head), body_.size() - (written_ - head))};
    return {asio::buffer(head_text_.data() + written_, head - written_), asio::buffer(body_.data(), body_.size())};
  }

  void close() {
    if (closed_) return;
    closed_ = true;
    if (std::exchange(waiting_, false)) catalogue_.table_builds().forget_owner(this);
    deadline_.cancel();
    boost::system::error_code ignored;
    socket_.shutdown(tcp::socket::shutdown_send, ignored);
    socket_.close(ignored);
  }

  tcp::socket socket_;
  Deadline deadline_;
  beast::flat_buffer buffer_;
  std::optional<HttpParser> parser_;
  bool request_begun_ = false;
  // The answer being written: its head, and its body, a span into answer_.
  HttpAnswer answer_;
  std::string head_text_;
  std::span<const uint8_t> body_;
  size_t written_ = 0;
  bool writing_ = false, keep_alive_ = false, closed_ = false;
  bool interim_ = false;       // what is being written is a 100 Continue, the request's answer to come
  bool waiting_ = false;       // for the tables the request in the parser needs
  HttpAnswer pending_answer_;  // its 503, sent if the request deadline passes first
  const Catalogue& catalogue_;
  const HttpLimits& limits_;
  HttpStats& stats_;
  const void* server_;  // the TableBuilds group of this server's connections
};

// The answer to a connection over the limit, written once without waiting: it fits any socket buffer.
void refuse(tcp::socket& socket) {
  static const std::string text = [] {
    const HttpAnswer answer = error_answer(503, "the server is at its connection limit; try again later");
    std::string head;
    write_response_head(answer, false, 11, head);
    const std::span<const uint8_t> body = answer.body();
    return head + std::string(body.begin(), body.end());
  }();
  boost::system::error_code ignored;
  socket.non_blocking(true, ignored);
  socket.write_some(asio::buffer(text), ignored);
  socket.shutdown(tcp::socket::shutdown_both, ignored);
  socket.close(ignored);
}

}  // namespace

struct HttpServer::Impl {
  Impl(std::shared_ptr<const Catalogue> c, const HttpLimits& l)
      : catalogue(std::move(c)), limits(l), contexts(make_contexts(l.threads)) {
    for (const auto& io : contexts) work.push_back(asio::make_work_guard(*io));
  }

  // One thread each: asio skips the hand-offs between threads (concurrency hint 1).
  static std::vector<std::unique_ptr<asio::io_context>> make_contexts(unsigned threads) {
    std::vector<std::unique_ptr<asio::io_context>> contexts;
    for (unsigned i = 0; i < io_thread_count(threads); ++i) contexts.push_back(std::make_unique<asio::io_context>(1));
    return contexts;
  }

  // Connections take the threads in turn; a connection stays on its thread.
  void accept() {
    asio::io_context& io = *contexts[next_context++ % contexts.size()];
    acceptor.async_accept(io, [this](const boost::system::error_code& ec, tcp::socket socket) {
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
      const asio::any_io_executor executor = socket.get_executor();
      auto connection = std::make_shared<HttpConnection>(std::move(socket), *catalogue, limits, stats, this);
      // Started on its own thread, where all its handlers run.
      asio::post(executor, [connection] { connection->start(); });
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
  size_t next_context = 0;
  // Last: destroyed first, with the connections their handlers still hold (they use the members above);
  // the acceptor and the backoff timer, on the first context, before the contexts.
  std::vector<std::unique_ptr<asio::io_context>> contexts;
  std::vector<asio::executor_work_guard<asio::io_context::executor_type>> work;
  tcp::acceptor acceptor{*contexts.front()};
  asio::steady_timer backoff{*contexts.front()};
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
  for (const auto& io : impl_->contexts) start_io_threads(*io, 1, impl_->threads, log_line);
}

// Connections hold no state worth a goodbye: the loops stop, and destroying them closes their sockets.
void HttpServer::stop() {
  {
    std::lock_guard<std::mutex> lock(impl_->stop_mutex);
    if (impl_->stopped) return;
    impl_->stopped = true;
  }
  // No table build may post to a loop once it is stopped and destroyed.
  impl_->catalogue->table_builds().forget_group(impl_.get());
  for (const auto& io : impl_->contexts) io->stop();
  for (std::thread& t : impl_->threads)
    if (t.joinable()) t.join();
}

const HttpStats& HttpServer::stats() const { return impl_->stats; }

}  // namespace pms::server
