
#include "protocol/dispatch.h"
#include "protocol/client_messages.h"
#include "protocol/framing.h"
#include "protocol/message_types.h"
#include "protocol/server_messages.h"
#include "protocol/stream_context.h"
// One entry point per direction: a frame's type picks the decoder, and a message that belongs to the
// other direction is as malformed as garbage.

namespace pms::protocol {
namespace {

[[noreturn]] void unexpected(MessageType type, const char* from) {
  throw ProtocolError(ErrorCode::bad_message, to_string(type) + ": not a message a " + from + " sends");
}

}  // namespace

ClientMessage decode_client_message(const Frame& frame, uint64_t max_resume_leaves) {
  switch (frame.type) {
    case MessageType::hello:
      return decode_hello(frame.payload);
    case MessageType::list:
      return decode_list(frame.payload);
    case MessageType::open:
      return decode_open(frame.payload, max_resume_leaves);
    case MessageType::view:
      return decode_view(frame.payload);
    case MessageType::close:
      return decode_close(frame.payload);
    case MessageType::dag_view:
      return decode_dag_view(frame.payload);
    case MessageType::ahead:
      return decode_ahead(frame.payload);
    default:
      unexpected(frame.type, "client");
  }
}

ServerMessage decode_server_message(const Frame& frame, const StreamContext* context) {
  switch (frame.type) {
    case MessageType::hello_ok:
      return decode_hello_ok(frame.payload);
    case MessageType::catalogue:
      return decode_catalogue(frame.payload);
    case MessageType::base:
      return decode_base(frame.payload);
    case MessageType::vsplits:
      if (!context) throw ProtocolError(ErrorCode::out_of_order, "VSPLITS: before any BASE");
      return decode_vsplits(frame.payload, *context);
    case MessageType::dag_ops:
      if (!context) throw ProtocolError(ErrorCode::out_of_order, "DAG_OPS: before any BASE");
      return decode_dag_ops(frame.payload, *context);
    case MessageType::codec:
      if (!context) throw ProtocolError(ErrorCode::out_of_order, "CODEC: before any BASE");
      return decode_codec(frame.payload, *context);
    case MessageType::error:
      return decode_error(frame.payload);
    default:
      unexpected(frame.type, "server");
  }
}

}  // namespace pms::protocol
