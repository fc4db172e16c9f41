// The messages a server derives from a model: its BASE, its catalogue entry and the session context.
#pragma once
#include <cstdint>
#include <string>

#include "protocol/message_types.h"
#include "protocol/server_messages.h"
#include "protocol/stream_context.h"
#include "protocol/stream_mode.h"
#include "spm/hierarchy.h"

namespace pms::protocol {

// ---- building messages from a model --------------------------------------------------------------------

StreamContext stream_context(const Base& base);  // throws pms::Error for widths a decoder would reject
Base make_base(const ModelData& model, const std::string& name, uint32_t position_bits = kDefaultPositionBits);
// Whether a session of `mode` sends CODEC after BASE and split records in its VSPLITS packets: the
// sender-driven mode, not its plain option (whose packets are kim-lee-kobbelt §6.3's).
bool carries_split_records(StreamMode mode);
ModelInfo model_info(const ModelData& model, const std::string& name);  // counts from the hierarchy itself

}  // namespace pms::protocol
