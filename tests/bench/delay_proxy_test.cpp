// The viewer group's delaying relay: bytes come through intact and in order, each direction held at least
// its delay, and closing one side closes the other.
#include <gtest/gtest.h>

#include <utility>  // before asio with C++20

#include <boost/asio.hpp>
#include <chrono>
#include <string>
#include <thread>

#include "bench/delay_proxy.h"

namespace pms::bench {
namespace {

namespace asio = boost::asio;
using asio::ip::tcp;
using Clock = std::chrono::steady_clock;

// Echoes what one connection sends until it closes.
class EchoServer {
 public:
  EchoServer() : acceptor_(io_, tcp::endpoint(asio::ip::make_address("127.0.0.1"), 0)) {
    thread_ = std::thread([this] {
      tcp::socket socket = acceptor_.accept();
      char buffer[4096];
      boost::system::error_code ec;
      for (;;) {
        const size_t n = socket.read_some(asio::buffer(buffer), ec);
        if (ec) break;
        asio::write(socket, asio::buffer(buffer, n), ec);
        if (ec) break;
      }
    });
  }
  ~EchoServer() { thread_.join(); }
  uint16_t port() const { return acceptor_.local_endpoint().port(); }

 private:
  asio::io_context io_;
  tcp::acceptor acceptor_;
  std::thread thread_;
};

TEST(DelayProxy, RelaysInOrderAndHoldsEachDirection) {
  EchoServer echo;
  DelayProxy proxy(echo.port(), std::chrono::milliseconds(40));
  asio::io_context io;
  tcp::socket socket(io);
  socket.connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"), proxy.port()));
  std::string sent;
  for (int i = 0; i < 2000; ++i) sent += std::to_string(i) + ",";
  const Clock::time_point start = Clock::now();
  asio::write(socket, asio::buffer(sent));
  std::string received(sent.size(), '\0');
  asio::read(socket, asio::buffer(received));
  const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
  EXPECT_EQ(received, sent);
  EXPECT_GE(seconds, 0.08) << "both directions are held 40 ms";
  socket.shutdown(tcp::socket::shutdown_both);
  socket.close();  // the echo server's read ends, so its thread returns
}

}  // namespace
}  // namespace pms::bench
