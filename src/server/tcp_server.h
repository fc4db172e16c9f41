// The TCP transport of the streaming server on Boost.Asio (kim-lee-kobbelt 2005 §5–6).
#pragma once
#include <cstdint>
#include <memory>
#include <string>

#include "server/catalogue.h"
#include "server/catalogue_slot.h"
#include "server/limits.h"
#include "server/stats.h"

namespace pms::server {

// TCP transport: `threads` I/O threads, one strand per connection, every read bounded by the frame
// limit and every wait by the idle timeout. A session answers from the catalogue in place when its
// connection was accepted.
class TcpServer {
 public:
  TcpServer(std::shared_ptr<const Catalogue> catalogue, const ServerLimits& limits, const std::string& host,
            uint16_t port);
  // Serving whatever catalogue `catalogues` holds when a connection is accepted (a reload swaps it).
  TcpServer(std::shared_ptr<CatalogueSlot> catalogues, const ServerLimits& limits, const std::string& host,
            uint16_t port);
  ~TcpServer();
  TcpServer(const TcpServer&) = delete;
  TcpServer& operator=(const TcpServer&) = delete;

  uint16_t port() const;  // the bound port (useful with port 0)
  void start();           // runs the I/O threads in the background
  void stop();            // closes every session and joins the threads
  void wait();            // blocks until stop() (from a signal handler or another thread)
  const ServerStats& stats() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace pms::server
