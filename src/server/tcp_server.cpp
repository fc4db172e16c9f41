// TCP transport of the sender-driven protocol on Boost.Asio. A small pool of I/O threads runs all
// connections; each connection's handlers run on its own strand, so a Session is only ever touched by one
// thread at a time. What drives a session (turns, slices, outbox, deadlines) is session_connection.h's,
// shared with the WebSocket; this file is the socket's part and the acceptor.
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
#include "server/session_connection.h"
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

// The TCP transport's part of a session's connection: raw bytes in, the outbox's frames out as they are,
// many per gathered write.
class Connection : public SessionConnection {
 public:
  Connection(tcp::socket socket, std::shared_ptr<const Catalogue> catalogue, const ServerLimits& limits,
             ServerStats& stats, Registry& registry, uint64_t id, const void* server)
      : SessionConnection(socket.get_executor(), std::move(catalogue), limits, stats, id, server),
        socket_(std::move(socket)),
        registry_(registry) {}

  void open() {
    boost::system::error_code ec;
    socket_.set_option(tcp::no_delay(true), ec);
    socket_.non_blocking(true, ec);  // write_now() must never block an I/O thread
    start();
  }

 private:
  tcp::socket& socket() override { return socket_; }
  void start_read() override;
  bool write_now() override;
  void wait_until_writable() override;
  void shut(bool reset) override;
  void on_closed() override;
  void on_outbox_dropped() override { front_written_ = 0; }
  bool pop_written(size_t n);
  std::shared_ptr<Connection> self() { return std::static_pointer_cast<Connection>(shared_from_this()); }

  tcp::socket socket_;
  Registry& registry_;
  std::array<uint8_t, 4096> read_buffer_;
  size_t front_written_ = 0;  // bytes of the outbox's first frame already in the socket
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

void Connection::start_read() {
  socket_.async_read_some(asio::buffer(read_buffer_),
                          [self = self()](const boost::system::error_code& ec, size_t n) {
                            self->pending_.read = false;
                            if (self->closed()) return;
                            if (ec) return self->close();  // peer gone or reset: nothing to answer
                            self->take_bytes(self->read_buffer_.data(), n);
                            self->serve();
                          });
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
    count_written(n, n);
    burst += n;
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

void Connection::wait_until_writable() {
  socket_.async_wait(tcp::socket::wait_write, [self = self()](const boost::system::error_code& ec) {
    self->pending_.writable = false;
    if (ec) return self->close();
    self->serve();
  });
}

// Bytes the peer did not take would keep the socket (and its kernel buffer) alive after the close: reset.
void Connection::shut(bool reset) {
  boost::system::error_code ignored;
  if (reset) socket_.set_option(asio::socket_base::linger(true, 0), ignored);
  socket_.shutdown(tcp::socket::shutdown_both, ignored);
  socket_.close(ignored);
}

void Connection::on_closed() { registry_.remove(self()); }

// The answer to a connection over the session limit, encoded once.
const std::vector<uint8_t>& server_full_frame() {
  static const std::vector<uint8_t> frame = protocol::encode(
      protocol::ErrorMessage{ErrorCode::server_full, "the server is at its session limit; try again later"});
  return frame;
}

}  // namespace

struct TcpServer::Impl {
  Impl(std::shared_ptr<CatalogueSlot> c, const ServerLimits& l)
      : catalogues(std::move(c)), limits(l), acceptor(io), backoff(io) {}

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
          std::make_shared<Connection>(std::move(socket), catalogues->get(), limits, stats, registry, ++next_id, this);
      registry.add(connection);
      stats.sessions_opened++;
      stats.sessions_active++;
      connection->open();
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

  std::shared_ptr<CatalogueSlot> catalogues;
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
    : TcpServer(std::make_shared<CatalogueSlot>(std::move(catalogue)), limits, host, port) {}

TcpServer::TcpServer(std::shared_ptr<CatalogueSlot> catalogues, const ServerLimits& limits, const std::string& host,
                     uint16_t port)
    : impl_(std::make_unique<Impl>(std::move(catalogues), limits)) {
  impl_->catalogues->get()->check_limits(limits);
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
  impl_->catalogues->table_builds().forget_group(impl_.get());
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
