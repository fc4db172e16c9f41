// TCP transport of the sender-driven protocol on Boost.Asio (asio's examples: one object per
// connection owning its socket and buffers, shared_from_this at the session boundary only, every read
// bounded, every wait timed). A small pool of I/O threads runs all connections; each connection's
// handlers run on its own strand, so a Session is only ever touched by one thread at a time.
#include <utility>  // before asio with C++20 (DESIGN.md §8)

#include <boost/asio.hpp>

#include <array>
#include <mutex>
#include <set>
#include <thread>

#include "common/error.h"
#include "server/server.h"

namespace pms::server {
namespace {

namespace asio = boost::asio;
using asio::ip::tcp;
using protocol::ErrorCode;

void update_max(std::atomic<uint64_t>& target, uint64_t value) {
  uint64_t seen = target.load(std::memory_order_relaxed);
  while (value > seen && !target.compare_exchange_weak(seen, value, std::memory_order_relaxed)) {}
}

class Registry;

class Connection : public std::enable_shared_from_this<Connection> {
 public:
  Connection(tcp::socket socket, std::shared_ptr<const Catalogue> catalogue, const ServerLimits& limits,
             ServerStats& stats, Registry& registry)
      : socket_(std::move(socket)),
        idle_(socket_.get_executor()),
        reader_(limits.max_client_message),
        session_(std::move(catalogue), limits),
        limits_(limits),
        stats_(stats),
        registry_(registry) {}

  void start();
  // Closes from any thread (server stop).
  void shutdown() {
    asio::post(socket_.get_executor(), [self = shared_from_this()] { self->close(); });
  }
  // Refuses a connection over the session limit with an ERROR, then closes.
  void refuse() {
    session_.abort_with(ErrorCode::server_full, "the server is at its session limit; try again later");
    write_next();
  }

 private:
  void read();
  void on_read(const boost::system::error_code& ec, size_t n);
  void pump_and_write();
  // Non-blocking writes until the outbox is empty (true) or the socket is full; adds what it wrote to `sent`.
  bool write_now(size_t& sent);
  void write_next();
  void arm_idle_timer();
  void close();

  tcp::socket socket_;
  asio::steady_timer idle_;
  std::array<uint8_t, 4096> read_buffer_;
  protocol::FrameReader reader_;
  Session session_;
  const ServerLimits& limits_;
  ServerStats& stats_;
  Registry& registry_;
  size_t queued_bytes_ = 0;
  size_t front_written_ = 0;  // bytes of the outbox's first frame already in the socket
  bool writing_ = false, reading_paused_ = false, closed_ = false;
};

// The live connections, so stop() can close them; counts sessions for the limit.
class Registry {
 public:
  bool add(const std::shared_ptr<Connection>& c, uint32_t max_sessions) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (live_.size() >= max_sessions) return false;
    live_.insert(c);
    return true;
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
  socket_.set_option(tcp::no_delay(true));
  socket_.non_blocking(true);  // write_now() must never block an I/O thread
  arm_idle_timer();
  read();
}

void Connection::arm_idle_timer() {
  idle_.expires_after(std::chrono::milliseconds(limits_.idle_timeout_ms));
  idle_.async_wait([self = shared_from_this()](const boost::system::error_code& ec) {
    if (ec || self->closed_) return;
    self->session_.abort_with(ErrorCode::timeout, "no message for " +
                                                      std::to_string(self->limits_.idle_timeout_ms) + " ms");
    self->pump_and_write();
  });
}

void Connection::read() {
  socket_.async_read_some(asio::buffer(read_buffer_),
                          [self = shared_from_this()](const boost::system::error_code& ec, size_t n) {
                            self->on_read(ec, n);
                          });
}

void Connection::on_read(const boost::system::error_code& ec, size_t n) {
  if (closed_) return;
  if (ec) return close();  // peer gone or reset: nothing to answer
  stats_.bytes_in += n;
  arm_idle_timer();
  try {
    reader_.feed(read_buffer_.data(), n);
    protocol::Frame frame;
    while (!session_.closing() && reader_.next(frame)) session_.receive(frame);
  } catch (const protocol::ProtocolError& e) {
    session_.abort_with(e.code, e.what());
  }
  pump_and_write();
  if (session_.closing()) return;  // the ERROR or CLOSE flushes, then the socket closes
  // Back-pressure: a client that does not read its answers is not read either.
  if (queued_bytes_ > limits_.send_queue_bytes) {
    reading_paused_ = true;
    return;
  }
  read();
}

void Connection::pump_and_write() {
  auto& outbox = session_.outbox();
  // Encode while the outbox is under the cap, and hand the bytes to the socket at once while it takes
  // them: an answer that fits the kernel's buffer then goes out in this one handler, rather than one trip
  // through the I/O threads' queue per outbox-full, behind every other busy session (E11's tail latency).
  // A burst is bounded, so one large answer does not hold an I/O thread from every other session.
  size_t burst = 0;
  for (;;) {
    queued_bytes_ = 0;
    for (const Buffer& b : outbox) queued_bytes_ += b->size();
    queued_bytes_ -= front_written_;
    while (queued_bytes_ <= limits_.send_queue_bytes && session_.pump()) queued_bytes_ += outbox.back()->size();
    update_max(stats_.peak_state_bytes, session_.state_bytes());
    update_max(stats_.peak_buffer_bytes, session_.state_bytes() - session_.tags().memory_bytes());
    if (writing_ || closed_ || outbox.empty() || burst >= limits_.send_burst_bytes || !write_now(burst)) break;
  }
  write_next();
}

bool Connection::write_now(size_t& sent) {
  auto& outbox = session_.outbox();
  while (!outbox.empty()) {
    const Buffer& front = outbox.front();
    boost::system::error_code ec;
    const size_t n = socket_.write_some(asio::buffer(*front) + front_written_, ec);
    if (ec == asio::error::would_block || ec == asio::error::try_again) return false;
    if (ec) {
      close();
      return false;
    }
    stats_.bytes_out += n;
    sent += n;
    front_written_ += n;
    if (front_written_ < front->size()) return false;  // the socket's buffer is full
    outbox.pop_front();
    front_written_ = 0;
  }
  return true;
}

void Connection::write_next() {
  auto& outbox = session_.outbox();
  if (writing_ || closed_) return;
  if (outbox.empty()) {
    if (session_.closing()) close();
    return;
  }
  writing_ = true;
  const Buffer front = outbox.front();
  asio::async_write(socket_, asio::buffer(*front) + front_written_,
                    [self = shared_from_this(), front](const boost::system::error_code& ec, size_t n) {
                      self->writing_ = false;
                      if (ec) return self->close();
                      self->stats_.bytes_out += n;
                      self->session_.outbox().pop_front();
                      self->front_written_ = 0;
                      self->pump_and_write();
                      if (self->reading_paused_ && !self->session_.closing() &&
                          self->queued_bytes_ <= self->limits_.send_queue_bytes) {
                        self->reading_paused_ = false;
                        self->read();
                      }
                    });
}

void Connection::close() {
  if (closed_) return;
  closed_ = true;
  stats_.splits_sent += session_.splits_sent();
  boost::system::error_code ignored;
  idle_.cancel();
  socket_.shutdown(tcp::socket::shutdown_both, ignored);
  socket_.close(ignored);
  stats_.sessions_active--;
  registry_.remove(shared_from_this());
}

}  // namespace

struct TcpServer::Impl {
  Impl(std::shared_ptr<const Catalogue> c, const ServerLimits& l)
      : catalogue(std::move(c)), limits(l), acceptor(io) {}

  void accept() {
    acceptor.async_accept(asio::make_strand(io), [this](const boost::system::error_code& ec, tcp::socket socket) {
      if (ec) {
        if (ec != asio::error::operation_aborted) accept();
        return;
      }
      auto connection = std::make_shared<Connection>(std::move(socket), catalogue, limits, stats, registry);
      stats.sessions_active++;
      if (registry.add(connection, limits.max_sessions)) {
        stats.sessions_opened++;
        connection->start();
      } else {
        stats.sessions_rejected++;
        registry.add(connection, UINT32_MAX);  // tracked until its ERROR is written
        connection->refuse();
      }
      accept();
    });
  }

  std::shared_ptr<const Catalogue> catalogue;
  ServerLimits limits;
  asio::io_context io;
  tcp::acceptor acceptor;
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
  boost::system::error_code ec;
  const auto address = asio::ip::make_address(host, ec);
  if (ec) fail(host, "not an IP address: " + ec.message());
  const tcp::endpoint endpoint(address, port);
  impl_->acceptor.open(endpoint.protocol(), ec);
  if (!ec) impl_->acceptor.set_option(tcp::acceptor::reuse_address(true), ec);
  if (!ec) impl_->acceptor.bind(endpoint, ec);
  if (!ec) impl_->acceptor.listen(asio::socket_base::max_listen_connections, ec);
  if (ec) fail(host + ":" + std::to_string(port), "cannot listen: " + ec.message());
}

TcpServer::~TcpServer() { stop(); }

uint16_t TcpServer::port() const { return impl_->acceptor.local_endpoint().port(); }

void TcpServer::start() {
  impl_->accept();
  unsigned n = impl_->limits.threads ? impl_->limits.threads : std::max(1u, std::thread::hardware_concurrency());
  for (unsigned i = 0; i < n; ++i) impl_->threads.emplace_back([this] { impl_->io.run(); });
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
  });
  for (const auto& c : impl_->registry.all()) c->shutdown();
  // Let the closes run, then end the loop.
  for (int i = 0; i < 200 && impl_->registry.size() > 0; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(5));
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
