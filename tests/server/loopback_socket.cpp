// The loopback client socket of the HTTP and WebSocket test clients (loopback_socket.h).
#include "loopback_socket.h"

#include <sys/socket.h>
#include <sys/time.h>

namespace pms::test {

namespace asio = boost::asio;
using asio::ip::tcp;

void connect_loopback(tcp::socket& socket, uint16_t port, const std::string& from, int timeout_ms,
                      int receive_buffer) {
  socket.open(tcp::v4());
  if (receive_buffer > 0) socket.set_option(asio::socket_base::receive_buffer_size(receive_buffer));
  socket.bind(tcp::endpoint(asio::ip::make_address(from), 0));
  socket.connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"), port));
  timeval tv{timeout_ms / 1000, (timeout_ms % 1000) * 1000};
  ::setsockopt(socket.native_handle(), SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
}

}  // namespace pms::test
