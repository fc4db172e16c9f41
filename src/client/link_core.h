// What the client's transports over a socket share (link.h's TCP Link, websocket_link.h's WebSocketLink):
// one I/O thread owns the stream and runs everything that touches it: the connect, the reads into a
// FrameReader, the writes of queued frames one after another, and the deadlines on all three (asio's
// chat_client shape, with the timeouts of its timeouts/ examples). The caller's threads only touch what the
// mutex guards and hand frames over with asio::post. A stream type says how it connects, writes and ends
// through StreamOps, which its transport's .cpp specializes before it instantiates LinkCore.
#pragma once
#include <utility>  // before asio with C++20 (docs/architecture.md, "Stack")

#include <boost/asio.hpp>

#include <array>
#include <condition_variable>
#include <deque>
#include <functional>
#include <mutex>
#include <string>
#include <thread>

#include "client/link.h"
#include "client/transport.h"
#include "common/error.h"
#include "protocol/framing.h"

namespace pms::client::link_core {

namespace asio = boost::asio;
using asio::ip::tcp;
using boost::system::error_code;
using std::chrono::milliseconds;

// socket(stream): its TCP socket; handshake(stream, host_port, path, max_message, done): what follows the
// TCP connect; write_some(stream, buffer, done); closed_by_peer(ec): the peer ended the stream in order.
template <class Stream>
struct StreamOps;

inline std::string in_ms(milliseconds d) { return std::to_string(d.count()) + " ms"; }

// A deadline on the I/O thread. Disarming can come after asio has already queued the expired wait's
// handler (its error code then says success), so each arming has a number and a stale expiry is dropped.
class Deadline {
 public:
  explicit Deadline(asio::io_context& io) : timer_(io) {}
  bool armed() const { return armed_; }

  void arm(milliseconds after, std::function<void()> on_expiry) {
    const uint64_t id = ++generation_;
    armed_ = true;
    timer_.expires_after(after);
    timer_.async_wait([this, id, on_expiry = std::move(on_expiry)](const error_code&) {
      if (id != generation_) return;
      armed_ = false;
      on_expiry();
    });
  }

  void disarm() {
    if (!armed_) return;
    armed_ = false;
    ++generation_;
    timer_.cancel();
  }

 private:
  asio::steady_timer timer_;
  uint64_t generation_ = 0;
  bool armed_ = false;
};

}  // namespace pms::client::link_core

namespace pms::client {

// What every stream's link shares: its thread and io_context, the queues the caller's threads reach under
// the mutex, and how the connection is lost. The stream's part is LinkCore's.
struct Link::Core {
  explicit Core(const LinkOptions& o) : options(o) {}
  virtual ~Core() = default;

  // Connects on the I/O thread; `path`: where a transport over HTTP asks for its stream (the WebSocket's).
  virtual void connect(const std::string& host, const std::string& port, const std::string& path) = 0;
  virtual void read() = 0;
  virtual void enqueue(std::vector<uint8_t> frame) = 0;
  virtual void close_socket() = 0;

  // ---- from any thread ----

  // With the mutex held. The first reason is the one reported; the socket is closed on its own thread,
  // which ends the read and the write in flight.
  void lose(const std::string& why) {
    if (gone) return;
    gone = true;
    reason = why;
    changed.notify_all();
    boost::asio::post(io, [this] { close_socket(); });
  }

  void lost(const std::string& why) {
    std::lock_guard<std::mutex> lock(mutex);
    lose(why);
  }

  [[noreturn]] void throw_lost() const { throw ConnectionError("server: connection lost: " + reason); }

  // Empty once the connection is open (even if it was lost again since: its frames are still to be read),
  // else why it could not be made.
  std::string wait_open() {
    std::unique_lock<std::mutex> lock(mutex);
    if (!changed.wait_for(lock, options.connect_timeout, [this] { return opened || gone; }))
      lose("no connection within " + link_core::in_ms(options.connect_timeout));
    return opened ? std::string() : reason;
  }

  // Never waits on the server: stopping the io_context drops whatever is still queued or in flight. The
  // one wait left is a host name still being looked up: asio joins its resolver thread when the io_context
  // goes, and getaddrinfo cannot be interrupted (a numeric address is never looked up).
  void stop() {
    if (!thread.joinable()) return;
    lost("closed by the client");
    io.stop();
    thread.join();
  }

  const LinkOptions options;
  boost::asio::io_context io;
  // Keeps run() going while nothing is in flight (reading paused by back-pressure, nothing to write).
  boost::asio::executor_work_guard<boost::asio::io_context::executor_type> work = boost::asio::make_work_guard(io);
  std::thread thread;

  // Shared, under the mutex.
  mutable std::mutex mutex;
  std::condition_variable changed;
  std::deque<protocol::Frame> queue;
  size_t queued_bytes = 0, send_queued_bytes = 0;
  bool read_paused = false;
  LinkCounters counters;
  bool opened = false, gone = false;
  std::string reason;
};

}  // namespace pms::client

namespace pms::client::link_core {

template <class Stream>
struct LinkCore : Link::Core {
  using Ops = StreamOps<Stream>;

  explicit LinkCore(const LinkOptions& o)
      : Core(o), stream(io), resolver(io), reader(o.max_message), write_deadline(io), frame_deadline(io) {}
  // The thread first: it uses the stream.
  ~LinkCore() override { stop(); }

  // ---- on the I/O thread ----

  void connect(const std::string& host, const std::string& port, const std::string& path) override {
    resolver.async_resolve(host, port, [this, host, port, path](const error_code& ec,
                                                                const tcp::resolver::results_type& endpoints) {
      if (ec) return connected(ec);
      asio::async_connect(Ops::socket(stream), endpoints,
                          [this, host, port, path](const error_code& e, const tcp::endpoint&) {
                            if (e) return connected(e);
                            Ops::handshake(stream, host + ":" + port, path, options.max_message,
                                           [this](const error_code& h) { connected(h); });
                          });
    });
  }

  void connected(const error_code& ec) {
    {
      std::lock_guard<std::mutex> lock(mutex);
      if (ec) return lose(ec.message());
      if (gone) return;  // the constructor stopped waiting
      opened = true;
      changed.notify_all();
    }
    error_code ignored;
    Ops::socket(stream).set_option(tcp::no_delay(true), ignored);
    read();
  }

  void read() override {
    // The read deadline runs per frame, from its first bytes, and only while this side is reading.
    if (reader.mid_frame() && !frame_deadline.armed())
      frame_deadline.arm(options.read_timeout,
                         [this] { lost("a frame stalled: not complete after " + in_ms(options.read_timeout)); });
    stream.async_read_some(asio::buffer(buffer), [this](const error_code& ec, size_t n) { on_read(ec, n); });
  }

  void on_read(const error_code& ec, size_t n) {
    if (Ops::closed_by_peer(ec))
      return lost(reader.mid_frame() ? "the server closed the connection mid-frame"
                                     : "the server closed the connection");
    if (ec) return lost(ec.message());
    bool completed = false, paused = false;
    {
      std::lock_guard<std::mutex> lock(mutex);
      counters.bytes_down += n;
      try {
        reader.feed(buffer.data(), n);
        protocol::Frame frame;
        while (reader.next(frame)) {
          counters.frames_down++;
          queued_bytes += frame.payload.size();
          queue.push_back(std::move(frame));
          completed = true;
        }
      } catch (const Error& e) {
        return lose(e.what());
      }
      changed.notify_all();
      // Back-pressure: the socket stays unread until receive() takes the queue below its limit.
      paused = read_paused = queued_bytes > options.max_queued_bytes;
    }
    if (completed || paused) frame_deadline.disarm();
    if (!paused) read();
  }

  void enqueue(std::vector<uint8_t> frame) override {
    outbox.push_back(std::move(frame));
    if (outbox.size() == 1) write();
  }

  // write_some rather than async_write: each chunk the kernel takes is progress and restarts the deadline,
  // so a big frame to a slow reader is fine and only a server that stops reading is lost.
  void write() {
    if (!write_deadline.armed())
      write_deadline.arm(options.write_timeout,
                         [this] { lost("no write progress for " + in_ms(options.write_timeout)); });
    const std::vector<uint8_t>& frame = outbox.front();
    Ops::write_some(stream, asio::buffer(frame.data() + written, frame.size() - written),
                    [this](const error_code& ec, size_t n) { on_written(ec, n); });
  }

  void on_written(const error_code& ec, size_t n) {
    if (ec) return lost(ec.message());
    write_deadline.disarm();
    written += n;
    if (written == outbox.front().size()) {
      std::lock_guard<std::mutex> lock(mutex);
      send_queued_bytes -= outbox.front().size();
      outbox.pop_front();
      written = 0;
    }
    if (!outbox.empty()) write();
  }

  void close_socket() override {
    error_code ignored;
    resolver.cancel();
    Ops::socket(stream).shutdown(tcp::socket::shutdown_both, ignored);
    Ops::socket(stream).close(ignored);
  }

  // The I/O thread's own.
  Stream stream;
  tcp::resolver resolver;
  std::array<uint8_t, 64 * 1024> buffer;
  protocol::FrameReader reader;
  std::deque<std::vector<uint8_t>> outbox;
  size_t written = 0;  // bytes of outbox.front() already sent
  Deadline write_deadline, frame_deadline;
};

}  // namespace pms::client::link_core
