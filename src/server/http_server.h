// The HTTP transport of the receiver-driven mode (cheng-ooi 2008) on Boost.Beast: a stateless router over
// the catalogue (http_routes.h), so it needs no session and is not a SessionMode (docs/architecture.md).
#pragma once
#include <cstdint>
#include <memory>
#include <string>

#include "server/catalogue.h"
#include "server/limits.h"
#include "server/stats.h"

namespace pms::server {

// `threads` I/O threads of its own, one strand per connection; keep-alive; every read, write and idle
// wait under a deadline; at most max_connections at once (more get 503).
class HttpServer {
 public:
  HttpServer(std::shared_ptr<const Catalogue> catalogue, const HttpLimits& limits, const std::string& host,
             uint16_t port);
  ~HttpServer();
  HttpServer(const HttpServer&) = delete;
  HttpServer& operator=(const HttpServer&) = delete;

  uint16_t port() const;  // the bound port (useful with port 0)
  void start();           // runs the I/O threads in the background
  void stop();            // closes every connection and joins the threads
  const HttpStats& stats() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace pms::server
