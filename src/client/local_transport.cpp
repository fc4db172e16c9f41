#include "client/local_transport.h"

#include <utility>

namespace pms::client {

LocalTransport::LocalTransport(LocalEndpoint endpoint, uint32_t max_client_message, uint32_t max_server_message)
    : endpoint_(std::move(endpoint)), to_server_(max_client_message), to_client_(max_server_message) {}

void LocalTransport::send(const std::vector<uint8_t>& frame) {
  counters_.bytes_up += frame.size();
  counters_.frames_up++;
  to_server_.feed(frame.data(), frame.size());
  protocol::Frame f;
  while (to_server_.next(f)) endpoint_.receive(std::move(f));
}

std::optional<protocol::Frame> LocalTransport::receive(std::chrono::milliseconds) {
  protocol::Frame frame;
  while (!to_client_.next(frame)) {
    const std::shared_ptr<const std::vector<uint8_t>> bytes = endpoint_.next_frame();
    if (!bytes) return std::nullopt;
    counters_.bytes_down += bytes->size();
    counters_.frames_down++;
    to_client_.feed(bytes->data(), bytes->size());
  }
  return frame;
}

}  // namespace pms::client
