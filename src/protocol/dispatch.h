// Decoding any frame by its type, in the direction it travels.
#pragma once
#include <cstdint>
#include <variant>

#include "protocol/client_messages.h"
#include "protocol/framing.h"
#include "protocol/message_types.h"
#include "protocol/server_messages.h"
#include "protocol/stream_context.h"

namespace pms::protocol {

using ClientMessage = std::variant<Hello, List, Open, View, Close, DagView, Ahead>;
using ServerMessage = std::variant<HelloOk, Catalogue, Base, VSplits, ErrorMessage, DagOps, Codec>;
// Dispatch on the frame's type; a server type (or unknown byte) from a client is bad_message and vice
// versa. VSPLITS, DAG_OPS and CODEC need the context of the BASE before it: without one (nullptr) it is out_of_order.
ClientMessage decode_client_message(const Frame& frame, uint64_t max_resume_leaves = kDefaultMaxResumeLeaves);
ServerMessage decode_server_message(const Frame& frame, const StreamContext* context);

}  // namespace pms::protocol
