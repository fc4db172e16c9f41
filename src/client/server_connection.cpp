#include "client/server_connection.h"

#include <optional>
#include <utility>

#include "common/error.h"

namespace pms::client {

ServerConnection::ServerConnection(std::unique_ptr<Transport> transport, const std::string& client_name,
                                   std::chrono::milliseconds answer_timeout, Greeting greeting)
    : transport_(std::move(transport)), answer_timeout_(answer_timeout) {
  transport_->send(hello_frame(client_name));
  if (greeting == Greeting::await) (void)greeting_.take(receive_answer());  // anything but HELLO_OK fails there
}

protocol::Frame ServerConnection::receive_answer() {
  std::optional<protocol::Frame> frame = transport_->receive(answer_timeout_);
  if (!frame) throw ConnectionError("server: no answer within " + std::to_string(answer_timeout_.count()) + " ms");
  return std::move(*frame);
}

protocol::Frame ServerConnection::next() {
  for (;;)
    if (std::optional<protocol::Frame> frame = greeting_.take(receive_answer())) return std::move(*frame);
}

std::optional<protocol::Frame> ServerConnection::poll() {
  for (;;) {
    std::optional<protocol::Frame> frame = transport_->receive(std::chrono::milliseconds(0));
    if (!frame) return std::nullopt;
    if ((frame = greeting_.take(std::move(*frame)))) return frame;
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
