// What the TCP and HTTP servers share about sockets and threads: binding the listening socket, what the
// kernel still holds of a connection's answers, and the pool of threads that run one io_context.
#pragma once
#include <utility>  // before asio with C++20 (docs/architecture.md, "Stack")

#include <boost/asio.hpp>

#include <cstdint>
#include <functional>
#include <string>
#include <thread>
#include <vector>

namespace pms::server {

// Opens, binds (with SO_REUSEADDR) and listens on host:port; pms::Error naming the address (and `what`,
// unless empty) when host is not an IP address or the port cannot be had.
void listen_on(boost::asio::ip::tcp::acceptor& acceptor, const std::string& host, uint16_t port,
               const std::string& what);

// Bytes written to `socket` that the peer has not acknowledged yet (SIOCOUTQ): what the kernel still holds
// for it. A write that succeeded only moved bytes there; a peer that never reads leaves them.
uint64_t unsent_bytes(boost::asio::ip::tcp::socket& socket);

// The threads `count` asks for: itself, or one per core for 0.
unsigned io_thread_count(unsigned count);

// Starts `count` threads (0 = one per core) that run `io` until it stops. A handler that throws is
// logged through `log` and the thread runs on: one connection's fault never stops the loop.
void start_io_threads(boost::asio::io_context& io, unsigned count, std::vector<std::thread>& threads,
                      const std::function<void(const std::string&)>& log);

}  // namespace pms::server
