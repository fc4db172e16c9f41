// What decoding a session's vsplit packets needs to know about its model, derived by both ends from BASE.
#pragma once
#include <cstdint>
#include <functional>
#include <memory>

#include "protocol/position_grid.h"
#include "spm/hierarchy.h"
#include "spm/split_codec.h"
#include "spm/vertex_id.h"

namespace pms::protocol {

// What a vsplit packet's decoder needs to know about the model: id widths, the position grid and which
// attributes travel. The server builds it from the BASE it sends, the client from the BASE it receives.
struct StreamContext {
  uint32_t root_count = 1;    // tree-ids are < root_count
  uint32_t tree_id_bits = 1;  // 1..32, enough for root_count - 1
  uint32_t node_id_bits = 0;  // the hierarchy's max depth (<= 63)
  PositionGrid grid;
  bool has_normals = false;
  bool has_colors = false;
  // Packets carry info_t and info_u. Not in a view-independent session (kim-lee-kobbelt §8, Fig. 9): its
  // client applies splits in PM order and never evaluates qrefine. Both ends set it from the OPEN's mode.
  bool has_refinement = true;
  // Packets are v_s's id and its compact split record (docs/protocol.md, "VSPLITS", "CODEC"): set by both
  // ends of a sender-driven session that is not plain, from the CODEC after BASE (carries_split_records).
  // `held` gives what the receiver holds about a vertex (SplitContext, as protocol/split_bands.h's
  // held_split_context reads it), false for one it does not hold; vertices a batch makes are known from
  // the batch itself.
  std::shared_ptr<const SplitCodec> records;
  std::function<bool(VertexId, SplitContext&)> held;
};

}  // namespace pms::protocol
