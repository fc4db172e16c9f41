#include "server/io_threads.h"

#include <linux/sockios.h>
#include <sys/ioctl.h>

#include <algorithm>
#include <exception>

#include "common/error.h"

namespace pms::server {

void listen_on(boost::asio::ip::tcp::acceptor& acceptor, const std::string& host, uint16_t port,
               const std::string& what) {
  namespace asio = boost::asio;
  boost::system::error_code ec;
  const auto address = asio::ip::make_address(host, ec);
  if (ec) fail(host, "not an IP address: " + ec.message());
  const asio::ip::tcp::endpoint endpoint(address, port);
  acceptor.open(endpoint.protocol(), ec);
  if (!ec) acceptor.set_option(asio::ip::tcp::acceptor::reuse_address(true), ec);
  if (!ec) acceptor.bind(endpoint, ec);
  if (!ec) acceptor.listen(asio::socket_base::max_listen_connections, ec);
  if (ec) fail(host + ":" + std::to_string(port), (what.empty() ? "" : what + ": ") + "cannot listen: " + ec.message());
}

uint64_t unsent_bytes(boost::asio::ip::tcp::socket& socket) {
  int unsent = 0;
  if (::ioctl(socket.native_handle(), SIOCOUTQ, &unsent) != 0) return 0;
  return uint64_t(std::max(unsent, 0));
}

unsigned io_thread_count(unsigned count) { return count ? count : std::max(1u, std::thread::hardware_concurrency()); }

void start_io_threads(boost::asio::io_context& io, unsigned count, std::vector<std::thread>& threads,
                      const std::function<void(const std::string&)>& log) {
  for (unsigned i = 0; i < io_thread_count(count); ++i)
    threads.emplace_back([&io, log] {
      for (;;) {
        try {
          io.run();
          return;
        } catch (const std::exception& e) {
          log(std::string("I/O thread: ") + e.what());
        }
      }
    });
}

}  // namespace pms::server
