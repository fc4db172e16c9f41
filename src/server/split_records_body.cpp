// Today's split records: the sender-driven packets (refinement info included) as one VSPLITS payload, so
// a client decodes them with decode_vsplits and the model's stream context.
#include "protocol/message_types.h"
#include "server/split_records_body.h"

namespace pms::server {

std::vector<uint8_t> split_records_body(const ServedModel& model, std::span<const uint32_t> nodes) {
  std::vector<uint8_t> frame = model.packets.encode(0, true, nodes);
  frame.erase(frame.begin(), frame.begin() + protocol::kFrameHeaderBytes);
  return frame;
}

}  // namespace pms::server
