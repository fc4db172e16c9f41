// A TCP relay on loopback that holds every byte for a fixed time in each direction: a link with a round
// trip of twice that and unlimited bandwidth, for the viewer group (a frame must not wait for the
// network, so it must not matter what the round trip is). Its own I/O thread; connections are relayed to
// 127.0.0.1:target_port, each direction's bytes in order, each chunk released `one_way` after it arrived.
#pragma once
#include <chrono>
#include <cstdint>
#include <memory>

namespace pms::bench {

class DelayProxy {
 public:
  DelayProxy(uint16_t target_port, std::chrono::milliseconds one_way);
  ~DelayProxy();  // closes every relayed connection and joins the thread
  DelayProxy(const DelayProxy&) = delete;
  DelayProxy& operator=(const DelayProxy&) = delete;

  uint16_t port() const;  // where clients connect

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace pms::bench
