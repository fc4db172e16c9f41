// The holding proxy (holding_proxy.h): one I/O thread; each accepted connection is a Pipe of two sockets.
// Upward, each read is written on before the next; downward, reads go on while holding and pile up in
// `out`, written to the client once released.
#include <utility>  // before asio with C++20 (docs/architecture.md, "Stack")

#include "holding_proxy.h"

#include <array>
#include <boost/asio.hpp>
#include <condition_variable>
#include <future>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace pms::test {

namespace asio = boost::asio;
using asio::ip::tcp;
using boost::system::error_code;

struct HoldingProxy::Impl {
  struct Pipe : std::enable_shared_from_this<Pipe> {
    Pipe(Impl& p, tcp::socket c) : proxy(p), client(std::move(c)), server(proxy.io) {}

    Impl& proxy;
    tcp::socket client, server;
    std::array<char, 16384> up{}, down{};
    std::string out;  // answer bytes not yet written to the client
    bool writing = false;

    void start() {
      server.async_connect({asio::ip::make_address("127.0.0.1"), proxy.upstream},
                           [self = shared_from_this()](const error_code& ec) {
                             if (ec) return self->close();
                             self->read_up();
                             self->read_down();
                           });
    }
    void close() {
      error_code ignored;
      client.close(ignored);
      server.close(ignored);
    }
    void read_up() {
      client.async_read_some(asio::buffer(up), [self = shared_from_this()](const error_code& ec, size_t n) {
        if (ec) return self->close();
        asio::async_write(self->server, asio::buffer(self->up, n), [self](const error_code& e, size_t) {
          if (e) return self->close();
          self->read_up();
        });
      });
    }
    void read_down() {
      server.async_read_some(asio::buffer(down), [self = shared_from_this()](const error_code& ec, size_t n) {
        if (ec) return self->close();  // what is held is dropped with the connection
        self->out.append(self->down.data(), n);
        self->proxy.count_held();
        self->flush();
        self->read_down();
      });
    }
    void flush() {
      if (proxy.holding || writing || out.empty()) return;
      writing = true;
      auto bytes = std::make_shared<std::string>(std::move(out));
      out.clear();
      asio::async_write(client, asio::buffer(*bytes), [self = shared_from_this(), bytes](const error_code& ec, size_t) {
        self->writing = false;
        if (ec) return self->close();
        self->flush();
      });
    }
  };

  explicit Impl(uint16_t up) : upstream(up), acceptor(io, {asio::ip::make_address("127.0.0.1"), 0}) {}

  void accept() {
    acceptor.async_accept([this](const error_code& ec, tcp::socket socket) {
      if (ec) return;
      auto pipe = std::make_shared<Pipe>(*this, std::move(socket));
      pipes.push_back(pipe);
      pipe->start();
      accept();
    });
  }

  // The bytes held now, for wait_held (read on the test's thread).
  void count_held() {
    uint64_t total = 0;
    for (const auto& weak : pipes)
      if (const auto pipe = weak.lock()) total += pipe->out.size();
    {
      std::lock_guard<std::mutex> lock(mutex);
      held = holding ? total : 0;
    }
    changed.notify_all();
  }

  // Runs `f` on the I/O thread and waits for it.
  template <typename F>
  void on_io(F f) {
    std::promise<void> done;
    asio::post(io, [&] {
      f();
      done.set_value();
    });
    done.get_future().wait();
  }

  uint16_t upstream;
  asio::io_context io;
  tcp::acceptor acceptor;
  std::vector<std::weak_ptr<Pipe>> pipes;
  bool holding = false;  // the I/O thread's
  mutable std::mutex mutex;
  mutable std::condition_variable changed;
  uint64_t held = 0;  // under mutex
  std::thread thread;
};

HoldingProxy::HoldingProxy(uint16_t upstream_port) : impl_(std::make_unique<Impl>(upstream_port)) {
  impl_->accept();
  impl_->thread = std::thread([this] { impl_->io.run(); });
}

HoldingProxy::~HoldingProxy() {
  impl_->io.stop();
  impl_->thread.join();
}

uint16_t HoldingProxy::port() const { return impl_->acceptor.local_endpoint().port(); }

std::string HoldingProxy::http_url() const { return "http://127.0.0.1:" + std::to_string(port()); }

void HoldingProxy::hold() {
  impl_->on_io([this] { impl_->holding = true; });
}

void HoldingProxy::release() {
  impl_->on_io([this] {
    impl_->holding = false;
    for (const auto& weak : impl_->pipes)
      if (const auto pipe = weak.lock()) pipe->flush();
    impl_->count_held();
  });
}

void HoldingProxy::drop() {
  impl_->on_io([this] {
    for (const auto& weak : impl_->pipes)
      if (const auto pipe = weak.lock()) {
        pipe->out.clear();
        pipe->close();
      }
    impl_->count_held();
  });
}

bool HoldingProxy::wait_held(uint64_t bytes, std::chrono::milliseconds deadline) const {
  std::unique_lock<std::mutex> lock(impl_->mutex);
  return impl_->changed.wait_for(lock, deadline, [&] { return impl_->held >= bytes; });
}

}  // namespace pms::test
