// The HTTP transport of the receiver-driven mode (cheng-ooi 2008) on Boost.Beast: a stateless router over
// the catalogue (http_routes.h), so it needs no session and is not a SessionMode (docs/architecture.md).
#pragma once
#include <cstdint>
#include <memory>
#include <string>

#include "server/catalogue.h"
#include "server/catalogue_slot.h"
#include "server/limits.h"
#include "server/stats.h"
#include "server/web_options.h"

namespace pms::server {

// `threads` I/O threads of its own, each connection on one of them; keep-alive; every read, write and idle
// wait under a deadline; at most max_connections at once and max_connections_per_address from one client
// (more get 503); each connection's turns and each client's work bounded (http_connection.h).
class HttpServer {
 public:
  HttpServer(std::shared_ptr<const Catalogue> catalogue, const HttpLimits& limits, const std::string& host,
             uint16_t port, const WebOptions& web = {});
  // Answering each request from the catalogue `catalogues` holds then (a reload swaps it); a WebSocket
  // session from the one in place at its upgrade.
  HttpServer(std::shared_ptr<CatalogueSlot> catalogues, const HttpLimits& limits, const std::string& host,
             uint16_t port, const WebOptions& web = {});
  ~HttpServer();
  HttpServer(const HttpServer&) = delete;
  HttpServer& operator=(const HttpServer&) = delete;

  uint16_t port() const;  // the bound port (useful with port 0)
  void start();           // runs the I/O threads in the background
  void stop();            // closes every connection and joins the threads
  const HttpStats& stats() const;
  const ServerStats& ws_sessions() const;  // the WebSocket's sessions, counted as the TCP server counts its own
  const WsStats& ws_stats() const;
  size_t tracked_addresses() const;  // client addresses with a connection or a budget debt now

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace pms::server
