#include "client/server_greeting.h"

#include "common/error.h"
#include "protocol/client_messages.h"

namespace pms::client {

std::vector<uint8_t> hello_frame(const std::string& client_name) {
  return protocol::encode(protocol::Hello{protocol::kProtocolVersion, client_name});
}

std::optional<protocol::Frame> ServerGreeting::take(protocol::Frame frame) {
  if (frame.type == protocol::MessageType::error) {
    const protocol::ErrorMessage e = protocol::decode_error(frame.payload);
    fail("server", protocol::to_string(e.code) + ": " + e.text);
  }
  if (greeted_) return frame;
  if (frame.type != protocol::MessageType::hello_ok)
    fail("server", "expected " + protocol::to_string(protocol::MessageType::hello_ok) + ", got " +
                       protocol::to_string(frame.type));
  hello_ok_ = protocol::decode_hello_ok(frame.payload);
  greeted_ = true;
  return std::nullopt;
}

}  // namespace pms::client
