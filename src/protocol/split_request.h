// The request code of the receiver-driven mode (cheng-ooi 2008 §4.3, Algorithm 1): a set of vertex ids,
// grouped by tree, with tree-id deltas and each tree's node ids as one recursive 2-bit subtree code, plus
// one descendant depth for the whole request. Byte for byte in docs/protocol.md, "Split request code".
// Shared with the browser build: single-threaded, no std::ranges algorithms, std::format or coroutines.
#pragma once
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "spm/vertex_id.h"

namespace pms::protocol {

// "Send the splits of `ids`, and of their descendants `depth` levels down" (cheng-ooi §4.3, last
// paragraph). The ids are an antichain (none is an ancestor of another): a client asks for leaves of
// what it holds. decode() returns them in code order: by tree, then left subtree before right.
struct SplitRequest {
  uint32_t depth = 0;
  std::vector<VertexId> ids;
  friend bool operator==(const SplitRequest&, const SplitRequest&) = default;
};

// What a decoder accepts: everything a peer sends is bounded before any work is done for it.
struct SplitRequestLimits {
  uint32_t root_count = 0;   // tree ids must be below it
  int max_node_depth = 62;   // deepest id the model can split (its node-id bits - 1); -1: none
  uint32_t max_ids = 4096;   // ids per request
  uint32_t max_depth = 8;    // the descendant depth
  size_t max_bytes = 16384;  // of the code
};

// The code of `request`: ids sorted and deduplicated first, so equal sets give equal bytes. Throws
// pms::Error for an empty set, a node id 0, or an id that is an ancestor of another.
std::vector<uint8_t> encode_split_request(const SplitRequest& request);

// Throws ProtocolError: too_large over max_bytes or max_ids; bad_id for a tree id >= root_count or an id
// deeper than max_node_depth; bad_message for a truncated code, a depth over max_depth, or anything
// that is not the one canonical encoding (non-zero padding, bytes after the end).
SplitRequest decode_split_request(std::span<const uint8_t> code, const SplitRequestLimits& limits);

// Sort order of decode(): by tree, then by the path from the root read as a binary fraction (pre-order).
bool code_order(VertexId a, VertexId b);

}  // namespace pms::protocol
