// A Session driven over a connection (asio's examples: one object per connection, shared_from_this at the
// session boundary only). Every peer is presumed hostile: a connection's turn on a thread is bounded in
// time (turn_us), its memory by the frame limit and the send queue, and every wait by a deadline
// (docs/operating.md). The transport's own part (tcp_server.cpp, ws_connection.cpp) is reading, writing
// and closing.
#include "server/session_connection.h"

#include <cstdio>

#include "protocol/message_types.h"
#include "server/http_cost.h"
#include "server/io_threads.h"

namespace pms::server {

namespace asio = boost::asio;
using protocol::ErrorCode;
using std::chrono::milliseconds;

namespace {
void log_line(const std::string& line) { std::fprintf(stderr, "pmstream serve: %s\n", line.c_str()); }
}  // namespace

SessionConnection::SessionConnection(const asio::any_io_executor& executor, std::shared_ptr<const Catalogue> catalogue,
                                     const ServerLimits& limits, ServerStats& stats, uint64_t id, const void* group)
    : reader_(limits.max_client_message),
      session_(std::move(catalogue), limits),
      limits_(limits),
      stats_(stats),
      id_(id),
      executor_(executor),
      timer_(executor),
      throttle_(executor),
      budget_(executor),
      group_(group) {
  if (limits.profile_phases) session_.profile_phases(&stats.phases);
}

void SessionConnection::start() {
  boost::system::error_code ec;
  const asio::ip::tcp::endpoint peer = socket().remote_endpoint(ec);
  peer_ = ec ? "unknown peer" : peer.address().to_string() + ":" + std::to_string(peer.port());
  connected_ = last_activity_ = last_message_ = refilled_ = Clock::now();
  tokens_ = limits_.max_message_rate;
  // An OPEN waiting for its tables gets its turn back when they are built; meanwhile the handshake
  // deadline runs on.
  session_.wake_with(group_, [weak = weak_from_this(), executor = executor_] {
    if (const auto self = weak.lock()) asio::post(executor, [self] { self->serve(); });
  });
  arm_timer();
  pending_.read = true;
  start_read();
}

void SessionConnection::shutdown() {
  asio::post(executor_, [self = shared_from_this()] { self->close(); });
}

size_t SessionConnection::take_bytes(const uint8_t* data, size_t n) {
  stats_.bytes_in += n;
  const bool was_mid_frame = reader_.mid_frame();
  const size_t ready = reader_.ready();
  try {
    reader_.feed(data, n);
  } catch (const std::exception& e) {  // out of memory for the frame: this session's fault only
    session_.abort_with(ErrorCode::internal, std::string("internal error: ") + e.what());
  }
  // A frame's deadline runs from its first byte; a read that completes frames starts the next one anew.
  if (reader_.mid_frame() && (!was_mid_frame || reader_.ready() > ready)) frame_started_ = Clock::now();
  return reader_.ready() - std::min(ready, reader_.ready());
}

void SessionConnection::receive_frames(Clock::time_point turn_end) {
  protocol::Frame frame;
  // Checked per frame: a client that does not read its answers gets no more frames handled.
  while (!session_.closing() && !queue_full() && !pending_.budget && Clock::now() < turn_end && may_handle_a_frame()) {
    try {
      if (!reader_.next(frame)) return;
    } catch (const protocol::ProtocolError& e) {
      session_.abort_with(e.code, e.what());
      return;
    }
    last_activity_ = last_message_ = Clock::now();
    const size_t before = session_.outbox().size();
    const size_t bytes = protocol::kFrameHeaderBytes + frame.payload.size();
    session_.receive(std::move(frame));
    count_queued(before);
    spend(request_cost(session_.last_work(), 0, bytes));
  }
}

bool SessionConnection::may_handle_a_frame() {
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
void SessionConnection::throttle_until_a_token() {
  pending_.throttle = reads_paused_ = true;
  const double rate = limits_.max_message_rate;
  throttle_.expires_after(
      std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>((1 - tokens_) / rate)));
  throttle_.async_wait([self = shared_from_this()](const boost::system::error_code& ec) {
    self->pending_.throttle = false;
    if (!ec) self->serve();
  });
}

void SessionConnection::spend(double units) {
  const Clock::duration wait = charge(units);
  if (wait <= Clock::duration::zero() || pending_.budget) return;
  pending_.budget = reads_paused_ = true;
  budget_.expires_after(wait);
  budget_.async_wait([self = shared_from_this()](const boost::system::error_code& ec) {
    self->pending_.budget = false;
    if (!ec) self->serve();
  });
}

void SessionConnection::count_queued(size_t before) {
  const auto& outbox = session_.outbox();
  if (outbox.size() < before) {  // the session dropped what it had queued (no memory left for it)
    queued_bytes_ = 0;
    before = 0;
    on_outbox_dropped();
  }
  for (size_t i = before; i < outbox.size(); ++i) queued_bytes_ += outbox[i]->size();
  if (outbox.size() > before) start_write_deadline();
}

void SessionConnection::count_written(size_t frame_bytes, size_t socket_bytes) {
  if (socket_bytes > 0) last_activity_ = Clock::now();
  stats_.bytes_out += socket_bytes;
  written_ += socket_bytes;
  queued_bytes_ -= std::min(queued_bytes_, frame_bytes);
}

void SessionConnection::start_write_deadline() {
  if (write_deadline_.running()) return;
  write_deadline_.start(Clock::now(), bytes_taken());
  arm_timer();
}

uint64_t SessionConnection::bytes_taken() { return written_ - std::min<uint64_t>(written_, unsent_bytes(socket())); }

bool SessionConnection::all_delivered() {
  return session_.outbox().empty() && !sending() && unsent_bytes(socket()) == 0;
}

void SessionConnection::serve() {
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

void SessionConnection::serve_turn(Clock::time_point turn_end) {
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
  if (socket_full && !pending_.turn && !pending_.writable) {
    pending_.writable = true;
    wait_until_writable();
  }
  if (session_.closing()) return;
  if (queue_full()) return pause_reads();
  schedule_next(socket_full);
}

// Encode while the outbox is under the cap and the turn lasts, and hand the bytes to the transport at
// once while it takes them: an answer that fits the kernel's buffer then goes out in this one handler.
bool SessionConnection::encode_and_send(Clock::time_point turn_end) {
  bool socket_full = false;
  for (;;) {
    encode(turn_end);
    if (pending_.writable || closed()) return socket_full;
    socket_full = write_now();
    if (closed() || socket_full || queue_full() || !session_.has_work() || pending_.budget ||
        Clock::now() >= turn_end)
      return socket_full;
  }
}

void SessionConnection::encode(Clock::time_point turn_end) {
  while (!queue_full() && session_.has_work() && !pending_.budget && Clock::now() < turn_end) {
    const size_t before = session_.outbox().size();
    const size_t queued = queued_bytes_;
    session_.pump();
    count_queued(before);
    spend(double(session_.last_work()) + double(queued_bytes_ - std::min(queued, queued_bytes_)) / kBytesPerUnit);
  }
}

void SessionConnection::record_peaks() {
  update_max(stats_.peak_state_bytes, session_.state_bytes());
  update_max(stats_.peak_buffer_bytes, session_.state_bytes() - session_.front_bytes());
}

// The ERROR (or nothing, after CLOSE) gets a moment to leave.
void SessionConnection::start_draining() {
  if (phase_ == Phase::open) {
    phase_ = Phase::draining;
    close_by_ = Clock::now() + milliseconds(std::min<uint32_t>(1000, limits_.write_timeout_ms));
  }
  arm_timer();
}

// Back-pressure: neither read nor handle frames until the queue drains.
void SessionConnection::pause_reads() {
  reads_paused_ = true;
  arm_timer();
}

// This session's turn is over. With work left, others go first and a posted turn comes back to it; with
// none, it reads.
void SessionConnection::schedule_next(bool socket_full) {
  // A stream that failed (a bad header) has nothing ready, yet its ERROR is still to be raised.
  const bool frames_waiting = (reader_.ready() > 0 || reader_.failed()) && !pending_.throttle && !pending_.budget;
  // Bytes left although the transport was not full: the burst was used. A pending write wait serves the
  // connection itself once the socket takes more; posting turns meanwhile would spin on a peer that sends
  // without reading.
  const bool unsent = !socket_full && !pending_.writable && !session_.outbox().empty();
  if ((session_.has_work() && !pending_.budget) || frames_waiting || unsent) {
    post_turn();
  } else if (!pending_.read && reader_.ready() == 0 && !pending_.budget) {
    resume_reading();
  }
  arm_timer();
}

void SessionConnection::post_turn() {
  if (pending_.turn) return;
  pending_.turn = true;
  asio::post(executor_, [self = shared_from_this()] {
    self->pending_.turn = false;
    self->serve();
  });
}

// A frame's time stood still while reads were paused: it runs again from now.
void SessionConnection::resume_reading() {
  if (std::exchange(reads_paused_, false) && reader_.mid_frame()) frame_started_ = Clock::now();
  pending_.read = true;
  start_read();
}

SessionConnection::Clock::time_point SessionConnection::next_deadline() const {
  // Draining: look every 10 ms whether the peer has taken the last bytes, until close_by_.
  if (phase_ == Phase::draining) return std::min(close_by_, Clock::now() + milliseconds(10));
  Clock::time_point at = last_activity_ + milliseconds(limits_.idle_timeout_ms);
  if (!session_.opened()) at = std::min(at, connected_ + milliseconds(limits_.handshake_timeout_ms));
  if (frame_clock_running()) at = std::min(at, frame_started_ + milliseconds(limits_.frame_timeout_ms));
  if (write_deadline_.running()) at = std::min(at, write_deadline_.next_look());
  if (session_.can_park() && limits_.park_after_ms) at = std::min(at, last_message_ + milliseconds(limits_.park_after_ms));
  return at;
}

// Deadlines move later with activity; the timer is only moved when one comes earlier than it is set for,
// and a timer that fires early just sets itself again.
void SessionConnection::arm_timer() {
  if (closed()) return;
  const Clock::time_point at = next_deadline();
  if (at >= timer_at_) return;
  timer_at_ = at;
  timer_.expires_at(at);
  timer_.async_wait([self = shared_from_this()](const boost::system::error_code& ec) { self->on_timer(ec); });
}

void SessionConnection::on_timer(const boost::system::error_code& ec) {
  if (ec == asio::error::operation_aborted || closed()) return;  // moved earlier, or done
  timer_at_ = Clock::time_point::max();
  const Clock::time_point now = Clock::now();
  if (phase_ == Phase::draining) return on_close_deadline(now);
  const bool more_to_send = !session_.outbox().empty() || sending();
  if (write_deadline_.running() && write_deadline_.stalled(now, bytes_taken(), written_, more_to_send)) {
    timed_out_ = reset_ = true;
    return close();  // it does not read, so an ERROR would never arrive either
  }
  const std::string missed = missed_deadline(now);
  if (!missed.empty()) return time_out(missed);
  if (session_.can_park() && now >= last_message_ + milliseconds(limits_.park_after_ms)) {
    session_.park();
    stats_.fronts_parked++;
  }
  arm_timer();
}

void SessionConnection::on_close_deadline(Clock::time_point now) {
  const bool delivered = all_delivered();
  if (!delivered && now < close_by_) return arm_timer();
  reset_ = !delivered;  // its ERROR could not be delivered in time
  close();
}

// The text of the ERROR for the first deadline an open session has missed; empty while it missed none.
std::string SessionConnection::missed_deadline(Clock::time_point now) const {
  const auto past = [&](Clock::time_point since, uint32_t ms) { return now >= since + milliseconds(ms); };
  if (frame_clock_running() && past(frame_started_, limits_.frame_timeout_ms))
    return "a message took longer than " + std::to_string(limits_.frame_timeout_ms) + " ms to arrive";
  if (!session_.opened() && past(connected_, limits_.handshake_timeout_ms))
    return "no HELLO and OPEN within " + std::to_string(limits_.handshake_timeout_ms) + " ms";
  if (past(last_activity_, limits_.idle_timeout_ms))
    return "no message for " + std::to_string(limits_.idle_timeout_ms) + " ms";
  return {};
}

void SessionConnection::time_out(const std::string& why) {
  timed_out_ = true;
  session_.abort_with(ErrorCode::timeout, why);
  serve();
}

void SessionConnection::close() {
  if (closed()) return;
  phase_ = Phase::closed;
  count_outcome();
  timer_.cancel();
  throttle_.cancel();
  budget_.cancel();
  shut(reset_);
  stats_.sessions_active--;
  on_closed();
}

void SessionConnection::count_outcome() {
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

}  // namespace pms::server
