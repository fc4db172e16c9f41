// One connection to a streaming server, as every client mode and tool speaks it: HELLO, LIST, OPEN -> BASE,
// VIEW -> VSPLITS batches, each answer awaited under a deadline, or taken as it comes (poll). An ERROR from
// the server is a pms::Error with its code and text; a silent or lost server is a ConnectionError
// (transport.h).
#pragma once
#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "client/server_greeting.h"
#include "client/transport.h"
#include "common/camera.h"
#include "protocol/client_messages.h"
#include "protocol/framing.h"
#include "protocol/message_types.h"
#include "protocol/server_messages.h"
#include "protocol/stream_context.h"

namespace pms::client {

// Whether a new connection waits for HELLO_OK before anything else is sent. Pipelined, the next message
// (OPEN) follows HELLO at once and BASE comes one round trip after connecting; HELLO_OK, or the ERROR that
// refuses the HELLO, is then taken on the way to the first answer.
enum class Greeting : uint8_t { await, pipelined };

class ServerConnection {
 public:
  // Says HELLO over `transport` (already connected); with Greeting::await, waits for HELLO_OK.
  ServerConnection(std::unique_ptr<Transport> transport, const std::string& client_name,
                   std::chrono::milliseconds answer_timeout, Greeting greeting = Greeting::await);

  protocol::Catalogue list();
  protocol::Base open(const protocol::Open& open);
  // OPEN without waiting: BASE (and CODEC) come as frames from next() or poll().
  void send_open(const protocol::Open& open);
  // The CODEC after BASE in a session whose packets are split records.
  protocol::Codec next_codec(const protocol::StreamContext& context);
  void send_view(const Camera& camera, float tolerance, uint32_t frame);
  // The next VSPLITS batch (of this VIEW's answer or an earlier one's).
  protocol::VSplits next_batch(const protocol::StreamContext& context);
  // Any client frame (DAG_VIEW), and the next DAG_OPS of an answer.
  void send(const std::vector<uint8_t>& frame);
  protocol::DagOps next_dag_ops(const protocol::StreamContext& context);
  // The next frame, which must be of `type`.
  protocol::Frame expect(protocol::MessageType type);
  // The next frame of any type, under the answer deadline.
  protocol::Frame next();
  // A frame already received, if any, without waiting.
  std::optional<protocol::Frame> poll();

  LinkCounters counters() const { return transport_->counters(); }
  // Once it has come (pipelined: with the first answer).
  const protocol::HelloOk& hello_ok() const { return greeting_.hello_ok(); }

 private:
  protocol::Frame receive_answer();  // one frame under the answer deadline

  std::unique_ptr<Transport> transport_;
  std::chrono::milliseconds answer_timeout_;
  ServerGreeting greeting_;
};

}  // namespace pms::client
