#include "client/server_connection.h"

#include <optional>
#include <utility>

#include "common/error.h"

namespace pms::client {

ServerConnection::ServerConnection(std::unique_ptr<Transport> transport, const std::string& client_name,
                                   std::chrono::milliseconds answer_timeout, Greeting greeting)
    : transport_(std::move(transport)), answer_timeout_(answer_timeout) {
  transport_->send(protocol::encode(protocol::Hello{protocol::kProtocolVersion, client_name}));
  if (greeting == Greeting::await) (void)take(receive_answer());  // anything but HELLO_OK fails there
}

protocol::Frame ServerConnection::receive_answer() {
  std::optional<protocol::Frame> frame = transport_->receive(answer_timeout_);
  if (!frame) throw ConnectionError("server: no answer within " + std::to_string(answer_timeout_.count()) + " ms");
  return std::move(*frame);
}

std::optional<protocol::Frame> ServerConnection::take(protocol::Frame frame) {
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

protocol::Frame ServerConnection::next() {
  for (;;)
    if (std::optional<protocol::Frame> frame = take(receive_answer())) return std::move(*frame);
}

std::optional<protocol::Frame> ServerConnection::poll() {
  for (;;) {
    std::optional<protocol::Frame> frame = transport_->receive(std::chrono::milliseconds(0));
    if (!frame) return std::nullopt;
    if ((frame = take(std::move(*frame)))) return frame;
  }
}

protocol::Frame ServerConnection::expect(protocol::MessageType type) {
  protocol::Frame frame = next();
  if (frame.type != type)
    fail("server", "expected " + protocol::to_string(type) + ", got " + protocol::to_string(frame.type));
  return frame;
}

protocol::Catalogue ServerConnection::list() {
  transport_->send(protocol::encode(protocol::List{}));
  return protocol::decode_catalogue(expect(protocol::MessageType::catalogue).payload);
}

protocol::Base ServerConnection::open(const protocol::Open& open) {
  send_open(open);
  return protocol::decode_base(expect(protocol::MessageType::base).payload);
}

void ServerConnection::send_open(const protocol::Open& open) { transport_->send(protocol::encode(open)); }

void ServerConnection::send_view(const Camera& camera, float tolerance, uint32_t frame) {
  transport_->send(protocol::encode(protocol::View{camera, tolerance, frame}));
}

void ServerConnection::send(const std::vector<uint8_t>& frame) { transport_->send(frame); }

protocol::DagOps ServerConnection::next_dag_ops(const protocol::StreamContext& context) {
  return protocol::decode_dag_ops(expect(protocol::MessageType::dag_ops).payload, context);
}

protocol::Codec ServerConnection::next_codec(const protocol::StreamContext& context) {
  return protocol::decode_codec(expect(protocol::MessageType::codec).payload, context);
}

protocol::VSplits ServerConnection::next_batch(const protocol::StreamContext& context) {
  return protocol::decode_vsplits(expect(protocol::MessageType::vsplits).payload, context);
}

}  // namespace pms::client
