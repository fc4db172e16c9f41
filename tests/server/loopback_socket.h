// Test-only: a socket connected to a loopback server from a chosen loopback address (127.0.0.0/8 is all
// the machine's, so tests can be many clients), its reads timing out, its receive buffer chosen.
#pragma once
#include <utility>  // before asio with C++20

#include <boost/asio.hpp>
#include <cstdint>
#include <string>

namespace pms::test {

// `receive_buffer` > 0: SO_RCVBUF, set before connecting.
void connect_loopback(boost::asio::ip::tcp::socket& socket, uint16_t port, const std::string& from, int timeout_ms,
                      int receive_buffer);

}  // namespace pms::test
