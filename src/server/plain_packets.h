// The packets of kim-lee-kobbelt §6.3's variation (StreamMode::sender_plain, Fig. 10 middle column): a
// sender-driven batch whose packets name each split's cut vertices on the client's mesh (ActualCuts, the
// active ancestors of the fundamental ones) and carry no refinement info, for a client that applies every
// split as it arrives and never runs qrefine. The cut ids depend on the session's front, so these are
// encoded per batch rather than copied from PacketTable.
#pragma once
#include <cstdint>
#include <span>
#include <vector>

#include "protocol/stream_context.h"
#include "server/selective_streaming.h"
#include "spm/hierarchy.h"

namespace pms::server {

// VSPLITS{frame, final, the splits of `nodes`} with cuts[i] as node i's cut vertices. `wire` has no
// refinement info. pms::Error for a node that is not internal or cuts that do not match the nodes.
std::vector<uint8_t> encode_plain_batch(const ModelData& model, const protocol::StreamContext& wire, uint32_t frame,
                                        bool final, std::span<const uint32_t> nodes, std::span<const ActualCuts> cuts);

}  // namespace pms::server
