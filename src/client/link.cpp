// The client's TCP transport. One I/O thread owns the socket and runs everything that touches it: the
// connect, the reads into a FrameReader, the writes of queued frames one after another, and the deadlines
// on all three (asio's chat_client shape, with the timeouts of its timeouts/ examples). The caller's
// threads only touch what the mutex guards and hand frames over with asio::post.
#include <utility>  // before asio with C++20 (docs/architecture.md, "Stack")

#include <array>
#include <utility>  // before asio with C++20 (docs/architecture.md, "Stack")

#include <boost/asio.hpp>
#include <functional>
#include <thread>

#include "client/link.h"
#include "client/transport.h"
#include "common/error.h"
#include "protocol/framing.h"

namespace pms::client {

namespace asio = boost::asio;
using asio::ip::tcp;
using boost::system::error_code;
using std::chrono::milliseconds;

namespace {

std::string in_ms(milliseconds d) { return std::to_string(d.count()) + " ms"; }

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

LinkOptions queue_options(size_t max_queued_bytes, uint32_t max_message) {
  LinkOptions options;
  options.max_queued_bytes = max_queued_bytes;
  options.max_message = max_message;
  return options;
}

}  // namespace

struct Link::Impl {
  explicit Impl(const LinkOptions& o)
      : options(o), socket(io), resolver(io), reader(o.max_message), write_deadline(io), frame_deadline(io) {}
  ~Impl() { stop(); }

  // ---- on the I/O thread ----

  void connect(const std::string& host, const std::string& port) {
    resolver.async_resolve(host, port, [this](const error_code& ec, const tcp::resolver::results_type& endpoints) {
      if (ec) return connected(ec);
      asio::async_connect(socket, endpoints, [this](const error_code& e, const tcp::endpoint&) { connected(e); });
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
    socket.set_option(tcp::no_delay(true), ignored);
    read();
  }

  void read() {
    // The read deadline runs per frame, from its first bytes, and only while this side is reading.
    if (reader.mid_frame() && !frame_deadline.armed())
      frame_deadline.arm(options.read_timeout,
                         [this] { lost("a frame stalled: not complete after " + in_ms(options.read_timeout)); });
    socket.async_read_some(asio::buffer(buffer), [this](const error_code& ec, size_t n) { on_read(ec, n); });
  }

  void on_read(const error_code& ec, size_t n) {
    if (ec == asio::error::eof)
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

  void enqueue(std::vector<uint8_t> frame) {
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
    socket.async_write_some(asio::buffer(frame.data() + written, frame.size() - written),
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

  void close_socket() {
    error_code ignored;
    resolver.cancel();
    socket.shutdown(tcp::socket::shutdown_both, ignored);
    socket.close(ignored);
  }

  // ---- from any thread ----

  // With the mutex held. The first reason is the one reported; the socket is closed on its own thread,
  // which ends the read and the write in flight.
  void lose(const std::string& why) {
    if (gone) return;
    gone = true;
    reason = why;
    changed.notify_all();
    asio::post(io, [this] { close_socket(); });
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
      lose("no connection within " + in_ms(options.connect_timeout));
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
  asio::io_context io;
  // Keeps run() going while nothing is in flight (reading paused by back-pressure, nothing to write).
  asio::executor_work_guard<asio::io_context::executor_type> work = asio::make_work_guard(io);
  std::thread thread;

  // The I/O thread's own.
  tcp::socket socket;
  tcp::resolver resolver;
  std::array<uint8_t, 64 * 1024> buffer;
  protocol::FrameReader reader;
  std::deque<std::vector<uint8_t>> outbox;
  size_t written = 0;  // bytes of outbox.front() already sent
  Deadline write_deadline, frame_deadline;

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

Link::Link(const std::string& host, uint16_t port, const LinkOptions& options)
    : impl_(std::make_unique<Impl>(options)) {
  asio::post(impl_->io, [impl = impl_.get(), host, port] { impl->connect(host, std::to_string(port)); });
  impl_->thread = std::thread([impl = impl_.get()] { impl->io.run(); });
  if (const std::string why = impl_->wait_open(); !why.empty())
    throw ConnectionError(host + ":" + std::to_string(port) + ": cannot connect: " + why);
}

Link::Link(const std::string& host, uint16_t port, size_t max_queued_bytes, uint32_t max_message)
    : Link(host, port, queue_options(max_queued_bytes, max_message)) {}

Link::~Link() { close(); }

void Link::close() { impl_->stop(); }

void Link::send(const std::vector<uint8_t>& frame) {
  Impl& impl = *impl_;
  {
    std::lock_guard<std::mutex> lock(impl.mutex);
    const size_t limit = impl.options.max_send_queue_bytes;
    if (impl.send_queued_bytes > 0 && impl.send_queued_bytes + frame.size() > limit)
      impl.lose("send queue over " + std::to_string(limit) + " bytes: the server is not reading");
    if (impl.gone) impl.throw_lost();
    impl.send_queued_bytes += frame.size();
    impl.counters.bytes_up += frame.size();
    impl.counters.frames_up++;
  }
  asio::post(impl.io, [&impl, frame]() mutable { impl.enqueue(std::move(frame)); });
}

std::optional<protocol::Frame> Link::receive(milliseconds timeout) {
  Impl& impl = *impl_;
  std::unique_lock<std::mutex> lock(impl.mutex);
  if (!impl.changed.wait_for(lock, timeout, [&] { return !impl.queue.empty() || impl.gone; })) return std::nullopt;
  if (impl.queue.empty()) impl.throw_lost();
  protocol::Frame frame = std::move(impl.queue.front());
  impl.queue.pop_front();
  impl.queued_bytes -= frame.payload.size();
  if (impl.read_paused && impl.queued_bytes <= impl.options.max_queued_bytes) {
    impl.read_paused = false;
    asio::post(impl.io, [&impl] { impl.read(); });
  }
  return frame;
}

LinkCounters Link::counters() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->counters;
}

}  // namespace pms::client
