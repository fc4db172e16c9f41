// What a receiver-driven request names: the model's nodes of the ids asked for and of their descendants,
// in the order the answer carries their split records (docs/protocol.md, "Receiver-driven over HTTP").
#pragma once
#include <cstdint>
#include <vector>

#include "protocol/split_request.h"
#include "spm/hierarchy.h"

namespace pms::server {

// For each id in code order, its node and the internal nodes below it down to request.depth levels,
// breadth-first (a split before its children's). Throws ProtocolError: bad_id for an id that is not a
// node of the model or names a leaf (no split), too_large when the answer would exceed max_splits.
std::vector<uint32_t> requested_nodes(const ModelData& model, const protocol::SplitRequest& request,
                                      uint32_t max_splits);

}  // namespace pms::server
