// Cutting a byte stream into frames, whatever its chunking, bounded before anything is allocated.
// Shared with the browser build: single-threaded, no std::ranges algorithms, std::format or coroutines.
#pragma once
#include <cstddef>
#include <cstdint>
#include <deque>
#include <span>
#include <string>
#include <vector>

#include "protocol/message_types.h"

namespace pms::protocol {

struct Frame {
  MessageType type{};  // may hold a byte no enumerator names: the message decoders reject it
  std::vector<uint8_t> payload;
};

// Incremental decoder for a byte stream cut into arbitrary chunks. A header announcing more than
// `max_payload` bytes is refused as soon as its 5 bytes are in, before anything is allocated for it;
// payload buffers grow with the bytes that actually arrive, so a peer that announces 16 MiB and sends
// 10 bytes costs 10 bytes. Errors surface in stream order: next() first hands out the frames that came
// before the bad header, then throws ProtocolError(too_large), and keeps throwing (a stream cannot be
// resynchronized; later bytes are ignored). How the bytes were chunked never changes the outcome.
class FrameReader {
 public:
  explicit FrameReader(uint32_t max_payload = kDefaultMaxMessage);

  void feed(const uint8_t* data, size_t size);
  void feed(std::span<const uint8_t> bytes) { feed(bytes.data(), bytes.size()); }
  bool next(Frame& frame);  // pops the oldest complete frame; false if none; throws once failed and drained
  size_t ready() const { return ready_.size(); }
  bool failed() const { return !failed_.empty(); }
  // Bytes of an unfinished frame are buffered: a stream that ends now was cut mid-message.
  bool mid_frame() const { return header_fill_ > 0; }
  uint32_t max_payload() const { return max_payload_; }

 private:
  uint32_t max_payload_;
  uint8_t header_[kFrameHeaderBytes] = {};
  size_t header_fill_ = 0;
  uint32_t payload_size_ = 0;
  Frame current_;
  std::deque<Frame> ready_;
  std::string failed_;  // sticky error text
};

}  // namespace pms::protocol
