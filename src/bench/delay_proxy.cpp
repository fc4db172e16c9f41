#include "bench/delay_proxy.h"

#include <utility>  // before asio with C++20 (docs/architecture.md, "Stack")

#include <boost/asio.hpp>
#include <deque>
#include <thread>
#include <vector>

namespace pms::bench {
namespace {

namespace asio = boost::asio;
using asio::ip::tcp;
using Clock = std::chrono::steady_clock;

// One direction of a relayed connection: reads `from`, holds each chunk until its release time, writes
// it to `to` in order. Either side closing ends both.
class Pipe : public std::enable_shared_from_this<Pipe> {
 public:
  Pipe(std::shared_ptr<tcp::socket> from, std::shared_ptr<tcp::socket> to, std::chrono::milliseconds delay)
      : from_(std::move(from)), to_(std::move(to)), timer_(from_->get_executor()), delay_(delay) {}

  void start() { read(); }

 private:
  struct Chunk {
    Clock::time_point release;
    std::vector<uint8_t> bytes;
  };

  void read() {
    buffer_.resize(65536);
    from_->async_read_some(asio::buffer(buffer_), [self = shared_from_this()](boost::system::error_code ec, size_t n) {
      if (ec) return self->close();
      self->held_.push_back({Clock::now() + self->delay_, std::vector<uint8_t>(self->buffer_.begin(),
                                                                              self->buffer_.begin() + long(n))});
      if (self->held_.size() == 1 && !self->writing_) self->release_next();
      self->read();
    });
  }

  void release_next() {
    if (held_.empty()) return;
    writing_ = true;
    timer_.expires_at(held_.front().release);
    timer_.async_wait([self = shared_from_this()](boost::system::error_code ec) {
      if (ec) return self->close();
      asio::async_write(*self->to_, asio::buffer(self->held_.front().bytes),
                        [self](boost::system::error_code write_ec, size_t) {
                          if (write_ec) return self->close();
                          self->held_.pop_front();
                          self->writing_ = false;
                          self->release_next();
                        });
    });
  }

  void close() {
    boost::system::error_code ignored;
    from_->close(ignored);
    to_->close(ignored);
    timer_.cancel();
  }

  std::shared_ptr<tcp::socket> from_, to_;
  asio::steady_timer timer_;
  std::chrono::milliseconds delay_;
  std::vector<uint8_t> buffer_;
  std::deque<Chunk> held_;
  bool writing_ = false;
};

}  // namespace

struct DelayProxy::Impl {
  Impl(uint16_t target, std::chrono::milliseconds one_way)
      : target_port(target), delay(one_way), acceptor(io, tcp::endpoint(asio::ip::make_address("127.0.0.1"), 0)) {}

  void accept() {
    acceptor.async_accept([this](boost::system::error_code ec, tcp::socket socket) {
      if (ec) return;
      auto client = std::make_shared<tcp::socket>(std::move(socket));
      auto server = std::make_shared<tcp::socket>(io);
      server->async_connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"), target_port),
                            [this, client, server](boost::system::error_code connect_ec) {
                              if (connect_ec) return;
                              boost::system::error_code ignored;
                              client->set_option(tcp::no_delay(true), ignored);
                              server->set_option(tcp::no_delay(true), ignored);
                              std::make_shared<Pipe>(client, server, delay)->start();
                              std::make_shared<Pipe>(server, client, delay)->start();
                            });
      accept();
    });
  }

  uint16_t target_port;
  std::chrono::milliseconds delay;
  asio::io_context io;
  tcp::acceptor acceptor;
  std::thread thread;
};

DelayProxy::DelayProxy(uint16_t target_port, std::chrono::milliseconds one_way)
    : impl_(std::make_unique<Impl>(target_port, one_way)) {
  impl_->accept();
  impl_->thread = std::thread([io = &impl_->io] { io->run(); });
}

DelayProxy::~DelayProxy() {
  impl_->io.stop();
  impl_->thread.join();
}

uint16_t DelayProxy::port() const { return impl_->acceptor.local_endpoint().port(); }

}  // namespace pms::bench
