// The client's TCP transport: one I/O thread runs asio (reads into a FrameReader, writes posted from the
// caller), decoded frames wait in a bounded queue for the refinement thread (asio's chat_client shape).
#include <utility>  // before asio with C++20 (DESIGN.md §8)

#include <boost/asio.hpp>

#include <array>
#include <thread>

#include "client/client.h"
#include "common/error.h"

namespace pms::client {

namespace asio = boost::asio;
using asio::ip::tcp;

struct Link::Impl {
  Impl(size_t max_queued, uint32_t max_message) : socket(io), reader(max_message), max_queued_bytes(max_queued) {}

  void read() {
    socket.async_read_some(asio::buffer(buffer), [this](const boost::system::error_code& ec, size_t n) {
      if (ec) return lost(ec == asio::error::eof ? "the server closed the connection" : ec.message());
      std::unique_lock<std::mutex> lock(mutex);
      counters.bytes_down += n;
      try {
        reader.feed(buffer.data(), n);
        protocol::Frame frame;
        while (reader.next(frame)) {
          counters.frames_down++;
          queued_bytes += frame.payload.size();
          queue.push_back(std::move(frame));
        }
      } catch (const Error& e) {
        lock.unlock();
        return lost(e.what());
      }
      changed.notify_all();
      // Back-pressure: stop reading until the consumer catches up.
      changed.wait(lock, [this] { return queued_bytes <= max_queued_bytes || gone; });
      if (gone) return;
      lock.unlock();
      read();
    });
  }

  void lost(const std::string& why) {
    std::lock_guard<std::mutex> lock(mutex);
    if (!gone) {
      gone = true;
      reason = why;
    }
    changed.notify_all();
  }

  asio::io_context io;
  tcp::socket socket;
  std::array<uint8_t, 64 * 1024> buffer;
  protocol::FrameReader reader;
  std::thread thread;
  mutable std::mutex mutex;
  std::condition_variable changed;
  std::deque<protocol::Frame> queue;
  size_t queued_bytes = 0, max_queued_bytes;
  LinkCounters counters;
  bool gone = false;
  std::string reason;
};

Link::Link(const std::string& host, uint16_t port, size_t max_queued_bytes, uint32_t max_message)
    : impl_(std::make_unique<Impl>(max_queued_bytes, max_message)) {
  const std::string where = host + ":" + std::to_string(port);
  try {
    tcp::resolver resolver(impl_->io);
    asio::connect(impl_->socket, resolver.resolve(host, std::to_string(port)));
    impl_->socket.set_option(tcp::no_delay(true));
  } catch (const boost::system::system_error& e) {
    throw ConnectionError(where + ": cannot connect: " + e.code().message());
  }
  impl_->read();
  impl_->thread = std::thread([this] { impl_->io.run(); });
}

Link::~Link() { close(); }

void Link::close() {
  if (!impl_->thread.joinable()) return;
  impl_->lost("closed by the client");
  asio::post(impl_->io, [this] {
    boost::system::error_code ignored;
    impl_->socket.shutdown(tcp::socket::shutdown_both, ignored);
    impl_->socket.close(ignored);
  });
  impl_->io.stop();
  impl_->thread.join();
}

void Link::send(const std::vector<uint8_t>& frame) {
  {
    std::lock_guard<std::mutex> lock(impl_->mutex);
    if (impl_->gone) throw ConnectionError("server: connection lost: " + impl_->reason);
    impl_->counters.bytes_up += frame.size();
    impl_->counters.frames_up++;
  }
  // Written from the caller's thread: the I/O thread only reads, and a frame is small (VIEW, OPEN).
  boost::system::error_code ec;
  asio::write(impl_->socket, asio::buffer(frame), ec);
  if (ec) {
    impl_->lost(ec.message());
    throw ConnectionError("server: connection lost: " + ec.message());
  }
}

std::optional<protocol::Frame> Link::receive(std::chrono::milliseconds timeout) {
  std::unique_lock<std::mutex> lock(impl_->mutex);
  if (!impl_->changed.wait_for(lock, timeout, [this] { return !impl_->queue.empty() || impl_->gone; }))
    return std::nullopt;
  if (impl_->queue.empty()) throw ConnectionError("server: connection lost: " + impl_->reason);
  protocol::Frame frame = std::move(impl_->queue.front());
  impl_->queue.pop_front();
  impl_->queued_bytes -= frame.payload.size();
  impl_->changed.notify_all();
  return frame;
}

LinkCounters Link::counters() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->counters;
}

}  // namespace pms::client
