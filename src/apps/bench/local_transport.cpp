#include "apps/bench/local_transport.h"

#include "common/error.h"

namespace pms::app {

LocalTransport::LocalTransport(std::shared_ptr<const server::Catalogue> catalogue, const server::ServerLimits& limits)
    : session_(std::make_shared<server::Session>(std::move(catalogue), limits)),
      to_server_(limits.max_client_message),
      to_client_(protocol::kDefaultMaxMessage) {}

void LocalTransport::send(const std::vector<uint8_t>& frame) {
  counters_.bytes_up += frame.size();
  counters_.frames_up++;
  to_server_.feed(frame.data(), frame.size());
  protocol::Frame f;
  while (to_server_.next(f)) session_->receive(std::move(f));
}

std::optional<protocol::Frame> LocalTransport::receive(std::chrono::milliseconds) {
  protocol::Frame frame;
  while (!to_client_.next(frame)) {
    auto& outbox = session_->outbox();
    if (outbox.empty() && !session_->pump()) return std::nullopt;
    if (outbox.empty()) continue;
    const server::Buffer bytes = outbox.front();
    outbox.pop_front();
    counters_.bytes_down += bytes->size();
    counters_.frames_down++;
    to_client_.feed(bytes->data(), bytes->size());
  }
  return frame;
}

}  // namespace pms::app
