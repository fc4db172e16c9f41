// How a client reaches a server: frames out, frames in, and how a lost connection surfaces.
#pragma once
#include <chrono>
#include <cstdint>
#include <optional>
#include <vector>

#include "common/error.h"
#include "protocol/framing.h"
#include "protocol/message_types.h"

namespace pms::client {

struct LinkCounters {
  uint64_t bytes_up = 0, bytes_down = 0;  // whole frames, as on the wire
  uint64_t frames_up = 0, frames_down = 0;
  uint64_t payload_up() const { return bytes_up - frames_up * protocol::kFrameHeaderBytes; }
  uint64_t payload_down() const { return bytes_down - frames_down * protocol::kFrameHeaderBytes; }
};

// The connection could not be made or is gone (refused, closed, reset, or past a connect, write or answer
// deadline): the session can be resumed on a new one. Any other pms::Error (an ERROR from the server, a
// malformed message) is final.
struct ConnectionError : Error {
  using Error::Error;
};

// How a client reaches a server: frames out, frames in. TCP here (Link); the browser's WebSocket and
// the bench's in-process pipe are others.
class Transport {
 public:
  virtual ~Transport() = default;
  // Hands the frame over for sending (it may still be on its way when this returns); throws
  // ConnectionError once the connection is gone.
  virtual void send(const std::vector<uint8_t>& frame) = 0;
  // The next frame from the server; std::nullopt after `timeout`. Throws ConnectionError once the
  // connection is gone (with the reason) and nothing is left to read.
  virtual std::optional<protocol::Frame> receive(std::chrono::milliseconds timeout) = 0;
  virtual LinkCounters counters() const = 0;
};

}  // namespace pms::client
