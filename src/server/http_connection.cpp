// One HTTP connection (asio's examples: one object owning its socket, buffer and parser; shared_from_this at
// the connection boundary only). It holds no state between requests but its buffer and its budget: every
// answer comes from the routes over the catalogue. What a request costs the server is mostly system calls
// and wake-ups, not the routes (docs/internals.md, "The HTTP server"), so:
// - a connection lives on one I/O thread's io_context: no strand, no lock handed between threads;
// - an answer is written at once with one gather write (headers, body) on the non-blocking socket, and
//   only a peer that does not take it all is waited for;
// - requests already buffered (pipelined) are parsed and answered without reading again.
// Against a hostile peer (docs/operating.md, "HTTP"):
// - a turn on the thread ends after turn_us of work, inside one large answer if need be (its body is built
//   in slices, the rest on the connection's next turn, behind the other connections);
// - each request is charged its cost (http_cost.h) to the connection's and the client address's budgets;
//   over either, the connection is not read until it has refilled;
// - deadlines: idle_timeout_ms for the first byte of a request, request_timeout_ms for the rest of it,
//   write_timeout_ms for each piece of an answer to be taken, and for the bytes the kernel still holds to
//   drain; a connection closed at a deadline is reset, so its unsent bytes do not linger in the kernel.
#include "server/http_connection.h"

#include <array>
#include <cstdio>
#include <optional>

#include "server/drain_watch.h"
#include "server/http_cost.h"
#include "server/http_message.h"
#include "server/http_routes.h"
#include "server/io_threads.h"
#include "server/ws_connection.h"

namespace pms::server {
namespace {

namespace asio = boost::asio;
namespace beast = boost::beast;
using asio::ip::tcp;
using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

// Bytes read at a time. With the parser's limits it bounds the buffer: a request is parsed before more is read.
constexpr size_t kReadChunk = 16384;

void log_line(const std::string& line) { std::fprintf(stderr, "pmstream serve: http: %s\n", line.c_str()); }

// One timer for the nearest of a connection's deadlines. Pushing the deadline later, as every answer does
// with the idle deadline, is a store; the timer moves only when the deadline comes nearer, and when it fires
// early it waits again for the rest.
class Deadline {
 public:
  explicit Deadline(const asio::any_io_executor& executor) : timer_(executor) {}

  // `on_expiry` runs once `at` (the time set last) has passed, unless cancel() came first.
  template <class OnExpiry>
  void set(Clock::time_point at, OnExpiry on_expiry) {
    at_ = at;
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
  HttpConnection(tcp::socket socket, const ClientAddress& peer, HttpServerShared& shared)
      : socket_(std::move(socket)),
        deadline_(socket_.get_executor()),
        pause_(socket_.get_executor()),
        buffer_(size_t(shared.limits.max_header_bytes) + shared.limits.max_body_bytes + kReadChunk),
        drain_(shared.limits.write_timeout_ms),
        shared_(shared),
        limits_(shared.limits),
        stats_(shared.stats),
        peer_(peer),
        behind_proxy_(shared.limits.trusted_proxies.contains(peer)),
        // A trusted proxy carries many clients: its requests are charged to the clients it names.
        connection_budget_(behind_proxy_ ? 0 : shared.limits.connection_budget) {}

  ~HttpConnection() {
    shared_.catalogues.table_builds().forget_owner(this);
    if (handed_over_) return;  // the WebSocket holds the connection's place now
    shared_.addresses.close(peer_);
    stats_.connections_active--;
  }

  void start() {
    boost::system::error_code ignored;
    socket_.set_option(tcp::no_delay(true), ignored);
    // Sized explicitly: the kernel's own tuning lets a peer that never reads pin megabytes per connection.
    socket_.set_option(asio::socket_base::send_buffer_size(int(limits_.send_buffer_bytes)), ignored);
    socket_.set_option(asio::socket_base::receive_buffer_size(int(limits_.receive_buffer_bytes)), ignored);
    socket_.non_blocking(true, ignored);
    set_deadline(limits_.idle_timeout_ms);
    serve();
  }

 private:
  // ---- deadlines ----

  // The phase's deadline (idle, request or write), kept with the drain watch's looks on one timer.
  void set_deadline(uint32_t ms) {
    phase_until_ = Clock::now() + milliseconds(ms);
    arm_deadline();
  }

  void arm_deadline() {
    Clock::time_point at = phase_until_;
    if (drain_.running()) at = std::min(at, drain_.next_look());
    deadline_.set(at, [self = shared_from_this()] { self->on_deadline(); });
  }

  void on_deadline() {
    if (closed_) return;
    const Clock::time_point now = Clock::now();
    if (drain_.running() && drain_.stalled(now, bytes_taken(), bytes_written_, writing_)) return time_out();
    if (now < phase_until_) return arm_deadline();
    if (waiting_) return stop_waiting();
    if (paused_) return set_deadline(limits_.idle_timeout_ms);  // the server's wait, not the peer's silence
    time_out();
  }

  // A peer that sends too slowly would not read an answer either; its unsent bytes go with it.
  void time_out() {
    stats_.connections_timed_out++;
    stats_.connections_reset++;
    close(true);
  }

  uint64_t bytes_taken() { return bytes_written_ - std::min(bytes_written_, unsent_bytes(socket_)); }

  // ---- turns ----

  bool blocked() const { return closed_ || writing_ || waiting_ || paused_ || yielded_; }

  void serve() {
    if (blocked()) return;
    const Clock::time_point begin = Clock::now();
    try {
      serve_turn(begin + std::chrono::microseconds(limits_.turn_us));
    } catch (const std::exception& e) {  // out of memory for an answer: this connection's fault only
      log_line(std::string("internal error: ") + e.what());
      close(true);
    }
    update_max(stats_.longest_turn_us,
               uint64_t(std::chrono::duration_cast<std::chrono::microseconds>(Clock::now() - begin).count()));
  }

  // Answers the whole requests in the buffer until the turn ends, then reads more, unless an answer is
  // still being built or written.
  void serve_turn(Clock::time_point turn_end) {
    while (!blocked()) {
      if (building_) {
        if (!build_body(turn_end)) return yield();
        continue;
      }
      if (Clock::now() >= turn_end) return yield();
      if (!parser_) {
        parser_.emplace();
        bound_parser(*parser_, limits_);
        parser_->eager(false);  // the header alone: accept_header sees it before any byte of a body is taken
        request_bytes_ = 0;
      }
      beast::error_code ec;
      const size_t used = buffer_.size() ? parser_->put(buffer_.data(), ec) : 0;
      buffer_.consume(used);
      request_bytes_ += used;
      if (ec && ec != http::error::need_more) return refuse_request(ec);
      if (parser_->is_header_done() && !parser_->eager() && !accept_header()) return;
      if (parser_->is_done()) {
        stats_.requests++;
        route_request(turn_end);
        continue;
      }
      if (used && buffer_.size()) continue;  // the header is in, the body goes on
      return read_more();
    }
  }

  // The connection's next turn comes after those of the other connections of its thread.
  void yield() {
    yielded_ = true;
    asio::post(socket_.get_executor(), [self = shared_from_this()] {
      self->yielded_ = false;
      self->serve();
    });
  }

  // ---- reading ----

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
      if (ec) return self->close(false);  // the deadline closed the socket
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
    if (ec) return close(false);  // the peer left
    serve();
  }

  // ---- answering ----

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

  // The request in the parser, routed; one whose tables are being built waits for them (wait_for_tables);
  // one whose body is large is built over turns (build_body).
  void route_request(Clock::time_point turn_end) {
    const auto target = parser_->get().target();
    if (is_ws_target(std::string_view(target.data(), target.size()))) return upgrade();
    HttpAnswer answer;
    try {
      catalogue_ = shared_.catalogues.get();  // held until the answer is sent: its body may be built from it
      answer = answer_request(*catalogue_, limits_, limits_.profile_phases ? &stats_.phases : nullptr, parser_->get(),
                              shared_.site);
    } catch (const std::exception& e) {  // out of memory for an answer: this request's fault only
      log_line(std::string("internal error: ") + e.what());
      answer = error_answer(500, "internal error");
    }
    if (answer.waits_for) return wait_for_tables(std::move(answer));
    if (answer.builder) {
      building_.emplace(std::move(answer));
      build_started_turn_ = turn_end;
      return;
    }
    finish_request(std::move(answer));
  }

  // The socket goes to a WebSocket session (ws_connection.h), with the connection's place in the limits.
  void upgrade() {
    if (std::optional<HttpAnswer> refusal = refuse_upgrade(parser_->get(), buffer_.size(), *shared_.ws))
      return finish_request(std::move(*refusal));
    const ClientAddress client = client_of(parser_->get());
    shared_.addresses.charge(client, request_cost(0, 0, request_bytes_), Clock::now());  // the session pays the debt
    closed_ = handed_over_ = true;
    deadline_.cancel();
    pause_.cancel();
    start_ws_connection(std::move(socket_), peer_, client, shared_, parser_->release());
    parser_.reset();
  }

  // True when the body is done and its answer sent on its way.
  bool build_body(Clock::time_point turn_end) {
    if (!building_->builder->build(turn_end)) return false;
    if (turn_end != build_started_turn_) stats_.sliced_answers++;
    HttpAnswer answer = std::move(*building_);
    building_.reset();
    answer.owned = answer.builder->take();
    answer.builder.reset();
    finish_request(std::move(answer));
    return true;
  }

  // One request at a time per connection, under the request deadline: the connection stops reading and
  // routes it again when a builder wakes it (on_tables_settled), or answers the 503 at the deadline.
  void wait_for_tables(HttpAnswer answer) {
    const asio::any_io_executor executor = socket_.get_executor();
    TableWaiter waiter{this, shared_.group, [weak = weak_from_this(), executor] {
                         asio::post(executor, [weak] {
                           if (const auto self = weak.lock()) self->on_tables_settled();
                         });
                       }};
    if (shared_.catalogues.table_builds().request(*answer.waits_for, answer.waits_for_mode, std::move(waiter)))
      return route_request(Clock::now() + std::chrono::microseconds(limits_.turn_us));  // built meanwhile
    waiting_ = true;
    pending_answer_ = std::move(answer);
    set_deadline(limits_.request_timeout_ms);
  }

  void on_tables_settled() {
    if (closed_ || !waiting_) return;
    waiting_ = false;
    route_request(Clock::now() + std::chrono::microseconds(limits_.turn_us));
    serve();
  }

  // The request deadline passed while its tables were being built: the 503 (Retry-After) goes out.
  void stop_waiting() {
    waiting_ = false;
    shared_.catalogues.table_builds().forget_owner(this);
    finish_request(std::move(pending_answer_));
    serve();
  }

  void finish_request(HttpAnswer answer, bool close = false) {
    const auto& request = parser_->get();
    const bool head = request.method() == http::verb::head;
    const bool keep_alive = request.keep_alive() && !close;
    const unsigned version = request.version();
    const ClientAddress client = client_of(request);
    parser_.reset();
    request_begun_ = false;
    const double cost = request_cost(answer.splits, answer.body().size(), request_bytes_);
    respond(std::move(answer), head, keep_alive, version);
    catalogue_.reset();  // the body holds what it needs of it: a reload's dropped models may go
    charge(client, cost);
  }

  ClientAddress client_of(const http::request<http::vector_body<uint8_t>>& request) const {
    if (!behind_proxy_) return peer_;
    std::string forwarded;  // every X-Forwarded-For field, in order, as one list (RFC 9110 §5.3)
    const auto [first, last] = request.equal_range("X-Forwarded-For");
    for (auto field = first; field != last; ++field) {
      if (!forwarded.empty()) forwarded += ',';
      forwarded.append(field->value().data(), field->value().size());
    }
    return forwarded_client(peer_, limits_.trusted_proxies, forwarded);
  }

  // ---- budgets ----

  // Over either budget, the connection is not read until both have refilled: its requests wait, they do
  // not fail.
  void charge(const ClientAddress& client, double cost) {
    const Clock::time_point now = Clock::now();
    const Clock::duration wait =
        std::max(connection_budget_.charge(cost, now), shared_.addresses.charge(client, cost, now));
    if (wait <= Clock::duration::zero() || closed_) return;
    stats_.budget_waits++;
    paused_ = true;
    pause_.expires_after(wait);
    pause_.async_wait([self = shared_from_this()](const boost::system::error_code& ec) {
      self->paused_ = false;
      if (!ec) self->serve();
    });
  }

  // ---- writing ----

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
      bytes_written_ += n;
      stats_.bytes_out += n;
      if (ec == asio::error::would_block || ec == asio::error::try_again) {
        set_deadline(limits_.write_timeout_ms);
        socket_.async_wait(tcp::socket::wait_write, [self = shared_from_this()](boost::system::error_code wait_ec) {
          if (wait_ec) return self->close(false);
          self->write();
          if (!self->writing_) self->serve();
        });
        return;
      }
      if (ec) return close(false);
    }
    writing_ = false;
    if (std::exchange(interim_, false)) return;  // the 100 Continue: the body comes next, under its deadline
    answer_ = {};
    if (!keep_alive_) return close(false);
    // An answer all written may still sit in the kernel: the peer must take it within the write deadline,
    // as it must take each piece of an answer that did not fit.
    if (unsent_bytes(socket_) > 0) drain_.start(Clock::now(), bytes_taken());
    set_deadline(limits_.idle_timeout_ms);
  }

  std::array<asio::const_buffer, 2> unwritten() const {
    const size_t head = head_text_.size();
    if (written_ >= head)
      return {asio::const_buffer(), asio::buffer(body_.data() + (written_ - head), body_.size() - (written_ - head))};
    return {asio::buffer(head_text_.data() + written_, head - written_), asio::buffer(body_.data(), body_.size())};
  }

  // `reset`: drop what the kernel still holds and send RST, instead of leaving the bytes to linger in
  // FIN-WAIT for minutes outside the connection limit.
  void close(bool reset) {
    if (closed_) return;
    closed_ = true;
    if (std::exchange(waiting_, false)) shared_.catalogues.table_builds().forget_owner(this);
    deadline_.cancel();
    pause_.cancel();
    boost::system::error_code ignored;
    if (reset) {
      socket_.set_option(asio::socket_base::linger(true, 0), ignored);
    } else {
      socket_.shutdown(tcp::socket::shutdown_send, ignored);
    }
    socket_.close(ignored);
  }

  tcp::socket socket_;
  std::shared_ptr<const Catalogue> catalogue_;  // the request's, from routing to its answer
  Deadline deadline_;
  asio::steady_timer pause_;  // over budget: the connection's next turn
  beast::flat_buffer buffer_;
  std::optional<HttpParser> parser_;
  size_t request_bytes_ = 0;  // of the request in the parser
  bool request_begun_ = false;
  // The answer being built over turns, and the turn it began in.
  std::optional<HttpAnswer> building_;
  Clock::time_point build_started_turn_{};
  // The answer being written: its head, and its body, a span into answer_.
  HttpAnswer answer_;
  std::string head_text_;
  std::span<const uint8_t> body_;
  size_t written_ = 0;
  uint64_t bytes_written_ = 0;  // to the socket, in the connection's life
  bool writing_ = false, keep_alive_ = false, closed_ = false;
  bool interim_ = false;  // what is being written is a 100 Continue, the request's answer to come
  bool handed_over_ = false;  // upgraded: the socket is a WebSocket session's
  bool paused_ = false;   // over budget
  bool yielded_ = false;  // its turn is over, the next one posted
  bool waiting_ = false;  // for the tables the request in the parser needs
  HttpAnswer pending_answer_;  // its 503, sent if the request deadline passes first
  // Deadlines: the phase's, and while the kernel holds answer bytes, the drain watch's.
  Clock::time_point phase_until_{};
  DrainWatch drain_;
  HttpServerShared& shared_;
  const HttpLimits& limits_;
  HttpStats& stats_;
  const ClientAddress peer_;
  const bool behind_proxy_;
  TokenBucket connection_budget_;
};

}  // namespace

ClientAddress peer_address(const tcp::socket& socket) {
  boost::system::error_code ec;
  const tcp::endpoint endpoint = socket.remote_endpoint(ec);
  ClientAddress address;
  if (ec) return address;  // gone already: the connection ends at its first read
  if (endpoint.address().is_v4()) {
    const auto v4 = endpoint.address().to_v4().to_bytes();
    address.bytes[10] = address.bytes[11] = 0xFF;
    std::copy(v4.begin(), v4.end(), address.bytes.begin() + 12);
  } else {
    address.bytes = endpoint.address().to_v6().to_bytes();
  }
  return address;
}

void start_http_connection(tcp::socket socket, const ClientAddress& peer, HttpServerShared& shared) {
  const asio::any_io_executor executor = socket.get_executor();
  auto connection = std::make_shared<HttpConnection>(std::move(socket), peer, shared);
  // Started on its own thread, where all its handlers run.
  asio::post(executor, [connection] { connection->start(); });
}

}  // namespace pms::server
