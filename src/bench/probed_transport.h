// A transport that tells its owner, before each frame is read, how many bytes the client has received so
// far: every frame before it has been handled by then (the client reads one frame at a time), so the
// client's mesh and counters agree at that moment. E6 samples the mesh there (quality_curve.h).
#pragma once
#include <functional>
#include <memory>

#include "client/transport.h"

namespace pms::bench {

class ProbedTransport : public client::Transport {
 public:
  using Probe = std::function<void(const client::LinkCounters& received_so_far)>;
  ProbedTransport(std::unique_ptr<client::Transport> inner, Probe probe)
      : inner_(std::move(inner)), probe_(std::move(probe)) {}

  void send(const std::vector<uint8_t>& frame) override { inner_->send(frame); }
  std::optional<protocol::Frame> receive(std::chrono::milliseconds timeout) override {
    probe_(inner_->counters());
    return inner_->receive(timeout);
  }
  client::LinkCounters counters() const override { return inner_->counters(); }

 private:
  std::unique_ptr<client::Transport> inner_;
  Probe probe_;
};

}  // namespace pms::bench
