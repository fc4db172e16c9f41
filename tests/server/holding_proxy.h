// A server that answers late, without a clock: a TCP proxy on loopback that passes what a client sends to
// the server at once and, while holding, keeps what the server answers until released. A test sees the
// answer reach the proxy (held_bytes) and a frame return without it: the frame did not wait for it.
#pragma once
#include <chrono>
#include <cstdint>
#include <memory>

#include "client/http_connection.h"

namespace pms::test {

class HoldingProxy {
 public:
  explicit HoldingProxy(uint16_t upstream_port);  // the server on 127.0.0.1
  ~HoldingProxy();
  HoldingProxy(const HoldingProxy&) = delete;
  HoldingProxy& operator=(const HoldingProxy&) = delete;

  uint16_t port() const;
  client::HttpUrl url() const { return client::HttpUrl{"127.0.0.1", port(), ""}; }
  std::string http_url() const;  // "http://127.0.0.1:PORT"

  void hold();     // answers from now on wait in the proxy
  void release();  // what waits goes on to the clients, and what comes later passes at once
  void drop();     // closes every connection, what is held with it: a server closing its kept-alive connections
  // Waits (up to `deadline`) until at least `bytes` of answers are held; false if they were not by then.
  bool wait_held(uint64_t bytes, std::chrono::milliseconds deadline = std::chrono::seconds(20)) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace pms::test
