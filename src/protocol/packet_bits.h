// Where a vsplit packet's bits go (kim-lee-kobbelt Table 2; bench E2).
#pragma once
#include <cstdint>

#include "protocol/stream_context.h"
#include "spm/split_record.h"
#include "spm/vertex_id.h"

namespace pms::protocol {

// Bits one vsplit packet takes inside a VSPLITS bit stream. topology = the ids of v_s, v̂_l, v̂_r and the
// 2-bit cut flags (children are implied); position = v_t's quantized position; refinement = info_t +
// info_u (0 when the context has no refinement info); attributes = normal and color.
struct PacketBits {
  uint32_t topology = 0, position = 0, refinement = 0, attributes = 0;
  uint32_t total() const { return topology + position + refinement + attributes; }
};
PacketBits packet_bits(const SplitRecord& split, const StreamContext& context);
// Bits of one id: tree-id, depth field and the depth path bits below the root.
uint32_t id_bits(VertexId id, const StreamContext& context);
// Width of the depth field: enough for 0..node_id_bits.
uint32_t depth_field_bits(uint32_t node_id_bits);

}  // namespace pms::protocol
