// What a client makes of a server's frames before its mode sees them, on every connection (the native
// ServerConnection and the browser's socket alike): an ERROR is a pms::Error with its code and text, the
// HELLO_OK that answers HELLO is kept, anything else before it is refused.
// Shared with the browser build: no I/O, single-threaded.
#pragma once
#include <optional>
#include <string>
#include <vector>

#include "protocol/framing.h"
#include "protocol/server_messages.h"

namespace pms::client {

// HELLO as this client says it.
std::vector<uint8_t> hello_frame(const std::string& client_name);

class ServerGreeting {
 public:
  // A frame as the server sent it: an ERROR thrown, HELLO_OK kept (nullopt then), anything else before
  // HELLO_OK refused; after it, the frame itself.
  std::optional<protocol::Frame> take(protocol::Frame frame);
  bool greeted() const { return greeted_; }
  const protocol::HelloOk& hello_ok() const { return hello_ok_; }

 private:
  protocol::HelloOk hello_ok_;
  bool greeted_ = false;
};

}  // namespace pms::client
