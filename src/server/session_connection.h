// What drives a server::Session over a connection, whatever carries its frames (the TCP server's sockets,
// the HTTP server's WebSockets): turns on an I/O thread, the session's slices, the outbox under
// back-pressure, the message rate, and every deadline (docs/operating.md). A transport derives from it and
// supplies how bytes come in (start_read, then take_bytes), how queued frames go out (write_now,
// wait_until_writable) and how the connection ends (shut).
#pragma once
#include <utility>  // before asio with C++20 (docs/architecture.md, "Stack")

#include <boost/asio.hpp>

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>

#include "protocol/framing.h"
#include "server/catalogue.h"
#include "server/drain_watch.h"
#include "server/limits.h"
#include "server/session.h"
#include "server/stats.h"

namespace pms::server {

class SessionConnection : public std::enable_shared_from_this<SessionConnection> {
 public:
  using Clock = std::chrono::steady_clock;

  SessionConnection(const boost::asio::any_io_executor& executor, std::shared_ptr<const Catalogue> catalogue,
                    const ServerLimits& limits, ServerStats& stats, uint64_t id, const void* group);
  virtual ~SessionConnection() = default;

  // The socket is connected and the transport ready: deadlines run, the first read starts.
  void start();
  // Closes from any thread (server stop).
  void shutdown();

 protected:
  // ---- what a transport supplies ----
  virtual boost::asio::ip::tcp::socket& socket() = 0;
  // Reads what comes next, then calls take_bytes (or close on an error); pending_.read is set meanwhile.
  virtual void start_read() = 0;
  // Hands queued frames to the transport until the outbox is empty (false), or it can take no more now
  // (true), or the burst is used (false, frames left).
  virtual bool write_now() = 0;
  // Serves again once the transport can take more (pending_.writable meanwhile).
  virtual void wait_until_writable() = 0;
  // Bytes handed over that are not in the socket yet (a WebSocket message being written).
  virtual bool sending() const { return false; }
  // Ends the transport; `reset` drops what the kernel holds (RST) for a peer that does not read.
  virtual void shut(bool reset) = 0;
  // The work units (http_cost.h) `units` cost the peer's budget: the wait before its session may go on (zero: now).
  virtual Clock::duration charge(double /*units*/) { return Clock::duration::zero(); }
  virtual void on_closed() {}
  // The session dropped its queued frames (no memory left for them): none is part-written any more.
  virtual void on_outbox_dropped() {}

  // ---- what a transport calls ----
  // Bytes read: fed to the frame reader; returns the frames they completed.
  size_t take_bytes(const uint8_t* data, size_t n);
  void serve();
  void close();
  bool closed() const { return phase_ == Phase::closed; }
  // Counts what the socket took: `frame_bytes` of the outbox's frames, as `socket_bytes` on the wire.
  void count_written(size_t frame_bytes, size_t socket_bytes);
  // Adds the frames queued since `before` (the outbox's size then) to the queue's byte count.
  void count_queued(size_t before);

  // What was asked of asio and has not called back yet, at most one of each: a turn starts only what is
  // not pending already.
  struct Pending {
    bool read = false;      // the transport's read
    bool writable = false;  // the transport is full: it serves again when it can take more
    bool turn = false;      // a posted serve(): the turn ended with work left and others go first
    bool throttle = false;  // the token bucket's timer: no frame is handled until it fires
    bool budget = false;    // the peer's work budget: nothing is handled or pumped until it has refilled
  };

  Pending pending_;
  protocol::FrameReader reader_;
  Session session_;
  const ServerLimits& limits_;
  ServerStats& stats_;
  uint64_t id_;
  std::string peer_;
  size_t queued_bytes_ = 0;
  bool reset_ = false;  // close with RST: the peer left bytes untaken past a deadline
  bool timed_out_ = false;

 private:
  // draining: the session is closing, and its last bytes (an ERROR, or nothing after CLOSE) get until
  // close_by_ to leave. closed: the transport is gone, and a handler that runs after it does nothing.
  enum class Phase { open, draining, closed };

  // A frame's deadline does not run while reads are paused: the peer could not send the rest.
  bool frame_clock_running() const { return reader_.mid_frame() && !reads_paused_; }
  bool all_delivered();
  bool queue_full() const { return queued_bytes_ > limits_.send_queue_bytes; }

  // One turn: frames in, pump, bytes out, then what comes next (a read, a write wait or another turn).
  void serve_turn(Clock::time_point turn_end);
  void receive_frames(Clock::time_point turn_end);
  // Message rate (a token bucket of max_message_rate per second): false when the next frame must wait, and
  // then the throttle timer resumes the session when it may go on.
  bool may_handle_a_frame();
  void throttle_until_a_token();
  // The peer's budget: after `units` of work, nothing more until its debt is repaid.
  void spend(double units);
  // Pumps and writes until the transport is full (true), the queue is, the work is done or the turn is over.
  bool encode_and_send(Clock::time_point turn_end);
  void encode(Clock::time_point turn_end);
  void record_peaks();
  void start_draining();
  void pause_reads();
  void schedule_next(bool socket_full);
  void post_turn();
  void resume_reading();
  // Bytes the peer has taken: what went into the socket less what the kernel still holds for it. The kernel
  // accepts megabytes for a peer that reads nothing, so a write that succeeds is no sign of progress.
  uint64_t bytes_taken();
  void start_write_deadline();
  // Deadlines: one timer, set to the earliest that applies; a check when it fires.
  Clock::time_point next_deadline() const;
  void arm_timer();
  void on_timer(const boost::system::error_code& ec);
  void on_close_deadline(Clock::time_point now);
  std::string missed_deadline(Clock::time_point now) const;
  void time_out(const std::string& why);
  void count_outcome();

  boost::asio::any_io_executor executor_;
  boost::asio::steady_timer timer_;
  boost::asio::steady_timer throttle_;
  boost::asio::steady_timer budget_;
  Phase phase_ = Phase::open;
  double tokens_ = 0;
  Clock::time_point refilled_;
  bool reads_paused_ = false;  // throttled, or back-pressure: the kernel's buffers push back on the peer
  const void* group_;  // the TableBuilds group of this server's sessions
  Clock::time_point connected_, last_activity_, frame_started_, close_by_;
  Clock::time_point last_message_;  // the last frame from the peer: a session silent for park_after_ms parks
  DrainWatch write_deadline_{limits_.write_timeout_ms};  // runs while answer bytes wait, here or in the kernel
  uint64_t written_ = 0;  // bytes into the socket
  Clock::time_point timer_at_ = Clock::time_point::max();
};

}  // namespace pms::server
