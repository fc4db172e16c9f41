// TCP transport of the sender-driven protocol on Boost.Asio (asio's examples: one object per
// connection owning its socket and buffers, shared_from_this at the session boundary only). A small pool
// of I/O threads runs all connections; each connection's handlers run on its own strand, so a Session is
// only ever touched by one thread at a time.
// Every peer is presumed hostile: a connection's turn on a thread is bounded in time (turn_us), its
// memory by the frame limit and the send queue, and every wait by a deadline (docs/operating.md).
#include <utility>  // before asio with C++20 (docs/architecture.md, "Stack")

#include <array>
#include <utility>  // before asio with C++20 (docs/architecture.md, "Stack")

#include <boost/asio.hpp>
#include <cstdio>
#include <mutex>
#include <set>
#include <thread>

#include "common/error.h"
#include "protocol/framing.h"
#include "protocol/message_types.h"
#include "protocol/server_messages.h"
#include "server/catalogue.h"
#include "server/drain_watch.h"
#include "server/io_threads.h"
#include "server/limits.h"
#include "server/session.h"
#include "server/stats.h"
#include "server/tcp_server.h"

namespace pms::server {
namespace {

namespace asio = boost::asio;
using asio::ip::tcp;
using protocol::ErrorCode;
using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

void log_line(const std::string& line) { std::fprintf(stderr, "pmstream serve: %s\n", line.c_str()); }

class Registry;

class Connection : public std::enable_shared_from_this<Connection> {
 public:
  Connection(tcp::socket socket, std::shared_ptr<const Catalogue> catalogue, const ServerLimits& limits,
             ServerStats& stats, Registry& registry, uint64_t id, const void* server)
      : socket_(std::move(socket)),
        timer_(socket_.get_executor()),
        throttle_(socket_.get_executor()),
        reader_(limits.max_client_message),
        session_(std::move(catalogue), limits),
        limits_(limits),
        stats_(stats),
        registry_(registry),
        id_(id),
        server_(server) {}

  void start();
  // Closes from any thread (server stop).
  void shutdown() {
    asio::post(socket_.get_executor(), [self = shared_from_this()] { self->close(); });
  }

 private:
  // draining: the session is closing, and its last bytes (an ERROR, or nothing after CLOSE) get until
  // close_by_ to leave. closed: the socket is gone, and a handler that runs after it does nothing.
  enum class Phase { open, draining, closed };

  // What was asked of asio and has not called back yet, at most one of each: a turn starts only what is
  // not pending already.
  struct Pending {
    bool read = false;      // async_read_some
    bool writable = false;  // async_wait for the socket to take more: it was full
    bool turn = false;      // a posted serve(): the turn ended with work left and others go first
    bool throttle = false;  // the token bucket's timer: no frame is handled until it fires
  };

  bool closed() const { return phase_ == Phase::closed; }
  // A frame's deadline does not run while reads are paused: the peer could not send the rest.
  bool frame_clock_running() const { return reader_.mid_frame() && !reads_paused_; }
  bool all_delivered() const { return session_.outbox().empty() && bytes_taken() == written_; }
  bool queue_full() const { return queued_bytes_ > limits_.send_queue_bytes; }

  // One turn: frames in, pump, bytes out, then what comes next (a read, a write wait or another turn).
  void serve();
  void serve_turn(Clock::time_point turn_end);
  void read();
  void on_read(const boost::system::error_code& ec, size_t n);
  void receive_frames(Clock::time_point turn_end);
  // Message rate (a token bucket of max_message_rate per second): false when the next frame must wait, and
  // then the throttle timer resumes the session when it may go on.
  bool may_handle_a_frame();
  void throttle_until_a_token();
  // Pumps and writes until the socket is full (true), the queue is, the work is done or the turn is over.
  bool encode_and_send(Clock::time_point turn_end);
  void encode(Clock::time_point turn_end);
  // Non-blocking gathered writes until the outbox is empty, the burst is used, or the socket is full (true).
  bool write_now();
  bool pop_written(size_t n);
  void record_peaks();
  void start_draining();
  void wait_until_writable();
  void pause_reads();
  void schedule_next(bool socket_full);
  void post_turn();
  void resume_reading();
  // Adds the frames queued since `before` (the outbox's size then) to the queue's byte count.
  void count_queued(size_t before);
  // Bytes the peer has taken: what went into the socket less what the kernel still holds for it. The kernel
  // accepts megabytes for a peer that reads nothing, so a write that succeeds is no sign of progress.
  uint64_t bytes_taken() const;
  void start_write_deadline();
  // Deadlines: one timer, set to the earliest that applies; a check when it fires.
  Clock::time_point next_deadline() const;
  void arm_timer();
  void on_timer(const boost::system::error_code& ec);
  void on_close_deadline(Clock::time_point now);
  std::string missed_deadline(Clock::time_point now) const;
  void time_out(const std::string& why);
  void close();
  void count_outcome();

  tcp::socket socket_;
  asio::steady_timer timer_;
  asio::steady_timer throttle_;
  Phase phase_ = Phase::open;
  Pending pending_;
  double tokens_ = 0;
  Clock::time_point refilled_;
  bool reads_paused_ = false;  // throttled, or back-pressure: the kernel's buffers push back on the peer
  std::array<uint8_t, 4096> read_buffer_;
  protocol::FrameReader reader_;
  Session session_;
  const ServerLimits& limits_;
  ServerStats& stats_;
  Registry& registry_;
  uint64_t id_;
  const void* server_;  // the TableBuilds group of this server's sessions
  std::string peer_;
  Clock::time_point connected_, last_activity_, frame_started_, close_by_;
  DrainWatch write_deadline_{limits_.write_timeout_ms};  // runs while answer bytes wait, here or in the kernel
  uint64_t written_ = 0;  // bytes into the socket
  Clock::time_point timer_at_ = Clock::time_point::max();
  size_t queued_bytes_ = 0;
  size_t front_written_ = 0;  // bytes of the outbox's first frame already in the socket
  bool timed_out_ = false;
  bool reset_ = false;  // close with RST: the peer left bytes untaken past a deadline
};

// The live connections, so stop() can close them; counts sessions for the limit.
class Registry {
 public:
  void add(const std::shared_ptr<Connection>& c) {
    std::lock_guard<std::mutex> lock(mutex_);
    live_.insert(c);
  }
  void remove(const std::shared_ptr<Connection>& c) {
    std::lock_guard<std::mutex> lock(mutex_);
    live_.erase(c);
  }
  std::vector<std::shared_ptr<Connection>> all() {
    std::lock_guard<std::mutex> lock(mutex_);
    return {live_.begin(), live_.end()};
  }
  size_t size() {
    std::lock_guard<std::mutex> lock(mutex_);
    return live_.size();
  }

 private:
  std::mutex mutex_;
  std::set<std::shared_ptr<Connection>> live_;
};

void Connection::start() {
  boost::system::error_code ec;
  socket_.set_option(tcp::no_delay(true), ec);
  socket_.non_blocking(true, ec);  // write_now() must never block an I/O thread
  const tcp::endpoint peer = socket_.remote_endpoint(ec);
  peer_ = ec ? "unknown peer" : peer.address().to_string() + ":" + std::to_string(peer.port());
  connected_ = last_activity_ = refilled_ = Clock::now();
  tokens_ = limits_.max_message_rate;
  // An OPEN waiting for its tables gets its turn back when they are built; meanwhile the handshake
  // deadline runs on.
  session_.wake_with(server_, [weak = weak_from_this()] {
    if (const auto self = weak.lock()) asio::post(self->socket_.get_executor(), [self] { self->serve(); });
  });
  arm_timer();
  read();
}

void Connection::read() {
  pending_.read = true;
  socket_.async_read_some(asio::buffer(read_buffer_), [self = shared_from_this()](const boost::system::error_code& ec,
                                                                                  size_t n) { self->on_read(ec, n); });
}

void Connection::on_read(const boost::system::error_code& ec, size_t n) {
  pending_.read = false;
  if (closed()) return;
  if (ec) return close();  // peer gone or reset: nothing to answer
  stats_.bytes_in += n;
  const bool was_mid_frame = reader_.mid_frame();
  const size_t ready = reader_.ready();
  try {
    reader_.feed(read_buffer_.data(), n);
  } catch (const std::exception& e) {  // out of memory for the frame: this session's fault only
    session_.abort_with(ErrorCode::internal, std::string("internal error: ") + e.what());
  }
  // A frame's deadline runs from its first byte; a read that completes frames starts the next one anew.
  if (reader_.mid_frame() && (!was_mid_frame || reader_.ready() > ready)) frame_started_ = Clock::now();
  serve();
}

void Connection::receive_frames(Clock::time_point turn_end) {
  protocol::Frame frame;
  // Checked per frame: a client that does not read its answers gets no more frames handled.
  while (!session_.closing() && !queue_full() && Clock::now() < turn_end && may_handle_a_frame()) {
    try {
      if (!reader_.next(frame)) return;
    } catch (const protocol::ProtocolError& e) {
      session_.abort_with(e.code, e.what());
      return;
    }
    last_activity_ = Clock::now();
    const size_t before = session_.outbox().size();
    session_.receive(std::move(frame));
    count_queued(before);
  }
}

bool Connection::may_handle_a_frame() {
  if (pending_.throttle) return false;
  if (limits_.max_message_rate == 0 || reader_.ready() == 0) return true;
  const Clock::time_point now = Clock::now();
  const double rate = limits_.max_message_rate;
  tokens_ = std::min(rate, tokens_ + rate * std::chrono::duration<double>(now - refilled_).count());
  refilled_ = now;
  if (tokens_ < 1) {
    throttle_until_a_token();
    return false;
  }
  tokens_ -= 1;
  return true;
}

// No reads either meanwhile: the kernel's buffers push back on the peer.
void Connection::throttle_until_a_token() {
  pending_.throttle = reads_paused_ = true;
  const double rate = limits_.max_message_rate;
  throttle_.expires_after(
      std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>((1 - tokens_) / rate)));
  throttle_.async_wait([self = shared_from_this()](const boost::system::error_code& ec) {
    self->pending_.throttle = false;
    if (!ec) self->serve();
  });
}

void Connection::count_queued(size_t before) {
  const auto& outbox = session_.outbox();
  if (outbox.size() < before) {  // the session dropped what it had queued (no memory left for it)
    queued_bytes_ = 0;
    front_written_ = 0;
    before = 0;
  }
  for (size_t i = before; i < outbox.size(); ++i) queued_bytes_ += outbox[i]->size();
  if (outbox.size() > before) start_write_deadline();
}

void Connection::start_write_deadline() {
  if (write_deadline_.running()) return;
  write_deadline_.start(Clock::now(), bytes_taken());
  arm_timer();
}

uint64_t Connection::bytes_taken() const {
  return written_ - std::min<uint64_t>(written_, unsent_bytes(const_cast<tcp::socket&>(socket_)));
}

void Connection::serve() {
  if (closed()) return;
  const Clock::time_point begin = Clock::now();
  try {
    serve_turn(begin + std::chrono::microseconds(limits_.turn_us));
    const auto took = std::chrono::duration_cast<std::chrono::microseconds>(Clock::now() - begin).count();
    update_max(stats_.longest_turn_us, uint64_t(took));
  } catch (const std::exception& e) {  // the transport's own fault (e.g. no memory): this session ends
    if (!closed()) {
      log_line("session " + std::to_string(id_) + " (" + peer_ + "): internal error: " + e.what());
      stats_.sessions_failed++;
      close();
    }
  }
}

void Connection::serve_turn(Clock::time_point turn_end) {
  receive_frames(turn_end);
  const bool socket_full = encode_and_send(turn_end);
  if (closed()) return;
  record_peaks();
  if (session_.closing()) {
    start_draining();
    // Closed once the peer has taken the ERROR, or at close_by_.
    if (all_delivered()) return close();
  }
  // A posted turn writes again before a write wait could fire.
  if (socket_full && !pending_.turn) wait_until_writable();
  if (session_.closing()) return;
  if (queue_full()) return pause_reads();
  schedule_next(socket_full);
}

// Encode while the outbox is under the cap and the turn lasts, and hand the bytes to the socket at once
// while it takes them: an answer that fits the kernel's buffer then goes out in this one handler.
bool Connection::encode_and_send(Clock::time_point turn_end) {
  bool socket_full = false;
  for (;;) {
    encode(turn_end);
    if (pending_.writable || closed()) return socket_full;
    socket_full = write_now();
    if (closed() || socket_full || queue_full() || !session_.has_work() || Clock::now() >= turn_end) return socket_full;
  }
}

void Connection::encode(Clock::time_point turn_end) {
  while (!queue_full() && session_.has_work() && Clock::now() < turn_end) {
    const size_t before = session_.outbox().size();
    session_.pump();
    count_queued(before);
  }
}

bool Connection::write_now() {
  auto& outbox = session_.outbox();
  size_t burst = 0;
  std::array<asio::const_buffer, 64> gather;  // small frames (CATALOGUE, ERROR) go out many per syscall
  while (!outbox.empty()) {
    if (burst >= limits_.send_burst_bytes) return false;  // the rest in the next turn
    size_t count = 0;
    for (; count < gather.size() && count < outbox.size(); ++count)
      gather[count] = asio::buffer(*outbox[count]) + (count == 0 ? front_written_ : 0);
    boost::system::error_code ec;
    const size_t n = socket_.write_some(std::span(gather.data(), count), ec);
    if (ec == asio::error::would_block || ec == asio::error::try_again) return true;
    if (ec) {
      close();
      return false;
    }
    if (n > 0) last_activity_ = Clock::now();
    stats_.bytes_out += n;
    written_ += n;
    burst += n;
    queued_bytes_ -= std::min(queued_bytes_, n);
    if (!pop_written(n)) return true;
  }
  return false;
}

// Drops the frames the socket took whole; false when it took only part of one: its buffer is full.
bool Connection::pop_written(size_t n) {
  auto& outbox = session_.outbox();
  while (n > 0) {
    const size_t rest = outbox.front()->size() - front_written_;
    if (n < rest) {
      front_written_ += n;
      return false;
    }
    n -= rest;
    outbox.pop_front();
    front_written_ = 0;
  }
  return true;
}

void Connection::record_peaks() {
  update_max(stats_.peak_state_bytes, session_.state_bytes());
  update_max(stats_.peak_buffer_bytes, session_.state_bytes() - session_.front_bytes());
}

// The ERROR (or nothing, after CLOSE) gets a moment to leave.
void Connection::start_draining() {
  if (phase_ == Phase::open) {
    phase_ = Phase::draining;
    close_by_ = Clock::now() + milliseconds(std::min<uint32_t>(1000, limits_.write_timeout_ms));
  }
  arm_timer();
}

void Connection::wait_until_writable() {
  pending_.writable = true;
  socket_.async_wait(tcp::socket::wait_write, [self = shared_from_this()](const boost::system::error_code& ec) {
    self->pending_.writable = false;
    if (ec) return self->close();
    self->serve();
  });
}

// Back-pressure: neither read nor handle frames until the queue drains.
void Connection::pause_reads() {
  reads_paused_ = true;
  arm_timer();
}

// This session's turn is over. With work left, others go first and a posted turn comes back to it; with
// none, it reads.
void Connection::schedule_next(bool socket_full) {
  // A stream that failed (a bad header) has nothing ready, yet its ERROR is still to be raised.
  const bool frames_waiting = (reader_.ready() > 0 || reader_.failed()) && !pending_.throttle;
  // Bytes left although the socket was not full: the burst was used. A pending write wait serves the
  // connection itself once the socket takes more; posting turns meanwhile would spin on a peer that sends
  // without reading.
  const bool unsent = !socket_full && !pending_.writable && !session_.outbox().empty();
  if (session_.has_work() || frames_waiting || unsent) {
    post_turn();
  } else if (!pending_.read && reader_.ready() == 0) {
    resume_reading();
  }
  arm_timer();
}

void Connection::post_turn() {
  if (pending_.turn) return;
  pending_.turn = true;
  asio::post(socket_.get_executor(), [self = shared_from_this()] {
    self->pending_.turn = false;
    self->serve();
  });
}

// A frame's time stood still while reads were paused: it runs again from now.
void Connection::resume_reading() {
  if (std::exchange(reads_paused_, false) && reader_.mid_frame()) frame_started_ = Clock::now();
  read();
}

Clock::time_point Connection::next_deadline() const {
  // Draining: look every 10 ms whether the peer has taken the last bytes, until close_by_.
  if (phase_ == Phase::draining) return std::min(close_by_, Clock::now() + milliseconds(10));
  Clock::time_point at = last_activity_ + milliseconds(limits_.idle_timeout_ms);
  if (!session_.opened()) at = std::min(at, connected_ + milliseconds(limits_.handshake_timeout_ms));
  if (frame_clock_running()) at = std::min(at, frame_started_ + milliseconds(limits_.frame_timeout_ms));
  if (write_deadline_.running()) at = std::min(at, write_deadline_.next_look());
  return at;
}

// Deadlines move later with activity; the timer is only moved when one comes earlier than it is set for,
// and a timer that fires early just sets itself again.
void Connection::arm_timer() {
  if (closed()) return;
  const Clock::time_point at = next_deadline();
  if (at >= timer_at_) return;
  timer_at_ = at;
  timer_.expires_at(at);
  timer_.async_wait([self = shared_from_this()](const boost::system::error_code& ec) { self->on_timer(ec); });
}

void Connection::on_timer(const boost::system::error_code& ec) {
  if (ec == asio::error::operation_aborted || closed()) return;  // moved earlier, or done
  timer_at_ = Clock::time_point::max();
  const Clock::time_point now = Clock::now();
  if (phase_ == Phase::draining) return on_close_deadline(now);
  if (write_deadline_.running() && write_deadline_.stalled(now, bytes_taken(), written_, !session_.outbox().empty())) {
    timed_out_ = reset_ = true;
    return close();  // it does not read, so an ERROR would never arrive either
  }
  const std::string missed = missed_deadline(now);
  if (!missed.empty()) return time_out(missed);
  arm_timer();
}

void Connection::on_close_deadline(Clock::time_point now) {
  const bool delivered = all_delivered();
  if (!delivered && now < close_by_) return arm_timer();
  reset_ = !delivered;  // its ERROR could not be delivered in time
  close();
}

// The text of the ERROR for the first deadline an open session has missed; empty while it missed none.
std::string Connection::missed_deadline(Clock::time_point now) const {
  const auto past = [&](Clock::time_point since, uint32_t ms) { return now >= since + milliseconds(ms); };
  if (frame_clock_running() && past(frame_started_, limits_.frame_timeout_ms))
    return "a message took longer than " + std::to_string(limits_.frame_timeout_ms) + " ms to arrive";
  if (!session_.opened() && past(connected_, limits_.handshake_timeout_ms))
    return "no HELLO and OPEN within " + std::to_string(limits_.handshake_timeout_ms) + " ms";
  if (past(last_activity_, limits_.idle_timeout_ms))
    return "no message for " + std::to_string(limits_.idle_timeout_ms) + " ms";
  return {};
}

void Connection::time_out(const std::string& why) {
  timed_out_ = true;
  session_.abort_with(ErrorCode::timeout, why);
  serve();
}

void Connection::close() {
  if (closed()) return;
  phase_ = Phase::closed;
  count_outcome();
  boost::system::error_code ignored;
  // Bytes the peer did not take would keep the socket (and its kernel buffer) alive after the close: reset.
  if (reset_) socket_.set_option(asio::socket_base::linger(true, 0), ignored);
  timer_.cancel();
  throttle_.cancel();
  socket_.shutdown(tcp::socket::shutdown_both, ignored);
  socket_.close(ignored);
  stats_.sessions_active--;
  registry_.remove(shared_from_this());
}

void Connection::count_outcome() {
  stats_.splits_sent += session_.splits_sent();
  if (timed_out_) {
    stats_.sessions_timed_out++;
  } else if (const auto error = session_.error()) {
    if (*error == ErrorCode::internal) {
      stats_.sessions_failed++;
      log_line("session " + std::to_string(id_) + " (" + peer_ + "): " + session_.error_text());
    } else {
      stats_.protocol_errors++;
    }
  }
  if (session_.error()) stats_.errors_sent++;
}

// The answer to a connection over the session limit, encoded once.
const std::vector<uint8_t>& server_full_frame() {
  static const std::vector<uint8_t> frame = protocol::encode(
      protocol::ErrorMessage{ErrorCode::server_full, "the server is at its session limit; try again later"});
  return frame;
}

}  // namespace

struct TcpServer::Impl {
  Impl(std::shared_ptr<const Catalogue> c, const ServerLimits& l)
      : catalogue(std::move(c)), limits(l), acceptor(io), backoff(io) {}

  void accept() {
    acceptor.async_accept(asio::make_strand(io), [this](const boost::system::error_code& ec, tcp::socket socket) {
      if (ec == asio::error::operation_aborted) return;  // stopped
      if (ec) return accept_failed(ec);
      backoff_ms = 0;
      admit(std::move(socket));
      accept();
    });
  }

  // Out of descriptors or memory, accepting again at once would fail again at once: wait, longer each time.
  void accept_failed(const boost::system::error_code& ec) {
    stats.accept_failures++;
    backoff_ms = std::min<uint32_t>(std::max<uint32_t>(1, limits.accept_backoff_ms), backoff_ms ? backoff_ms * 2 : 10);
    if (backoff_ms >= limits.accept_backoff_ms || stats.accept_failures.load() == 1)
      log_line("accept: " + ec.message() + "; retrying in " + std::to_string(backoff_ms) + " ms");
    backoff.expires_after(milliseconds(backoff_ms));
    backoff.async_wait([this](const boost::system::error_code& wait_ec) {
      if (!wait_ec) accept();
    });
  }

  // Only this accept chain adds to the registry, so a count read here can only have fallen since.
  void admit(tcp::socket socket) {
    if (registry.size() >= limits.max_sessions) return refuse(socket);
    try {
      auto connection =
          std::make_shared<Connection>(std::move(socket), catalogue, limits, stats, registry, ++next_id, this);
      registry.add(connection);
      stats.sessions_opened++;
      stats.sessions_active++;
      connection->start();
    } catch (const std::exception& e) {
      log_line(std::string("accept: internal error: ") + e.what());
    }
  }

  // Answered without a session and closed at once: a refused peer holds nothing here. The ERROR fits any
  // socket buffer, so one non-blocking write delivers it.
  void refuse(tcp::socket& socket) {
    stats.sessions_refused++;
    boost::system::error_code ignored;
    socket.non_blocking(true, ignored);
    socket.write_some(asio::buffer(server_full_frame()), ignored);
    socket.shutdown(tcp::socket::shutdown_both, ignored);
    socket.close(ignored);
  }

  std::shared_ptr<const Catalogue> catalogue;
  ServerLimits limits;
  asio::io_context io;
  tcp::acceptor acceptor;
  asio::steady_timer backoff;
  uint32_t backoff_ms = 0;
  uint64_t next_id = 0;
  ServerStats stats;
  Registry registry;
  std::vector<std::thread> threads;
  std::mutex stop_mutex;
  std::condition_variable stopped_cv;
  bool stopped = false;
};

TcpServer::TcpServer(std::shared_ptr<const Catalogue> catalogue, const ServerLimits& limits, const std::string& host,
                     uint16_t port)
    : impl_(std::make_unique<Impl>(std::move(catalogue), limits)) {
  impl_->catalogue->check_limits(limits);
  listen_on(impl_->acceptor, host, port, "");
}

TcpServer::~TcpServer() { stop(); }

uint16_t TcpServer::port() const { return impl_->acceptor.local_endpoint().port(); }

void TcpServer::start() {
  impl_->accept();
  // A handler that throws ends its own session (Connection catches); the pool only keeps the thread alive.
  start_io_threads(impl_->io, impl_->limits.threads, impl_->threads, log_line);
}

void TcpServer::stop() {
  {
    std::lock_guard<std::mutex> lock(impl_->stop_mutex);
    if (impl_->stopped) return;
    impl_->stopped = true;
  }
  asio::post(impl_->io, [this] {
    boost::system::error_code ignored;
    impl_->acceptor.close(ignored);
    impl_->backoff.cancel();
  });
  for (const auto& c : impl_->registry.all()) c->shutdown();
  // Let the closes run (each handler is at most one turn), then end the loop.
  for (int i = 0; i < 100 && impl_->registry.size() > 0; ++i) std::this_thread::sleep_for(milliseconds(5));
  // No table build may post to the loop once it is stopped and destroyed.
  impl_->catalogue->table_builds().forget_group(impl_.get());
  impl_->io.stop();
  for (std::thread& t : impl_->threads)
    if (t.joinable()) t.join();
  impl_->stopped_cv.notify_all();
}

void TcpServer::wait() {
  std::unique_lock<std::mutex> lock(impl_->stop_mutex);
  impl_->stopped_cv.wait(lock, [this] { return impl_->stopped; });
}

const ServerStats& TcpServer::stats() const { return impl_->stats; }

}  // namespace pms::server
