// Framing (docs/protocol.md, "Conventions"): u32 LE payload length | u8 type | payload, read incrementally from a byte
// stream that arrives in arbitrary chunks (TCP segments, WebSocket messages, 1-byte test feeds).
#include <algorithm>

#include "protocol/framing.h"
#include "protocol/message_types.h"

namespace pms::protocol {
namespace {

// Grow payload buffers with the bytes that arrive, not with what the header announces: the first
// reservation is capped so a lying header costs nothing.
constexpr size_t kFirstReserve = 64 * 1024;

const char* hex_digits = "0123456789abcdef";

}  // namespace

std::string to_string(MessageType type) {
  switch (type) {
    case MessageType::hello:
      return "HELLO";
    case MessageType::list:
      return "LIST";
    case MessageType::open:
      return "OPEN";
    case MessageType::view:
      return "VIEW";
    case MessageType::close:
      return "CLOSE";
    case MessageType::dag_view:
      return "DAG_VIEW";
    case MessageType::ahead:
      return "AHEAD";
    case MessageType::dag_ops:
      return "DAG_OPS";
    case MessageType::codec:
      return "CODEC";
    case MessageType::hello_ok:
      return "HELLO_OK";
    case MessageType::catalogue:
      return "CATALOGUE";
    case MessageType::base:
      return "BASE";
    case MessageType::vsplits:
      return "VSPLITS";
    case MessageType::error:
      return "ERROR";
  }
  const unsigned byte = unsigned(type);
  return std::string("type 0x") + hex_digits[byte >> 4] + hex_digits[byte & 15];
}

std::string to_string(ErrorCode code) {
  switch (code) {
    case ErrorCode::bad_message:
      return "bad_message";
    case ErrorCode::unsupported_version:
      return "unsupported_version";
    case ErrorCode::unknown_model:
      return "unknown_model";
    case ErrorCode::bad_id:
      return "bad_id";
    case ErrorCode::too_large:
      return "too_large";
    case ErrorCode::out_of_order:
      return "out_of_order";
    case ErrorCode::server_full:
      return "server_full";
    case ErrorCode::timeout:
      return "timeout";
    case ErrorCode::internal:
      return "internal";
  }
  return "code " + std::to_string(unsigned(code));
}

FrameReader::FrameReader(uint32_t max_payload) : max_payload_(max_payload) {}

void FrameReader::feed(const uint8_t* data, size_t size) {
  if (!failed_.empty()) return;  // the stream cannot be resynchronized: the rest is ignored
  while (size > 0) {
    if (header_fill_ < kFrameHeaderBytes) {
      const size_t take = std::min(size, kFrameHeaderBytes - header_fill_);
      std::copy_n(data, take, header_ + header_fill_);
      header_fill_ += take;
      data += take;
      size -= take;
      if (header_fill_ < kFrameHeaderBytes) return;
      payload_size_ =
          uint32_t(header_[0]) | uint32_t(header_[1]) << 8 | uint32_t(header_[2]) << 16 | uint32_t(header_[3]) << 24;
      current_.type = MessageType(header_[4]);
      if (payload_size_ > max_payload_) {
        failed_ = "frame: " + to_string(current_.type) + " announces " + std::to_string(payload_size_) +
                  " payload bytes, the limit is " + std::to_string(max_payload_);
        return;
      }
      current_.payload.clear();
      current_.payload.reserve(std::min<size_t>(payload_size_, kFirstReserve));
    }
    const size_t take = std::min<size_t>(size, payload_size_ - current_.payload.size());
    current_.payload.insert(current_.payload.end(), data, data + take);
    data += take;
    size -= take;
    if (current_.payload.size() == payload_size_) {
      ready_.push_back(std::move(current_));
      current_ = Frame{};
      header_fill_ = 0;
    }
  }
}

bool FrameReader::next(Frame& frame) {
  if (ready_.empty()) {
    if (!failed_.empty()) throw ProtocolError(ErrorCode::too_large, failed_);
    return false;
  }
  frame = std::move(ready_.front());
  ready_.pop_front();
  return true;
}

}  // namespace pms::protocol
