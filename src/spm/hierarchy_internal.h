// Id derivation and lookup over plain arrays, shared by Hierarchy, ModelData and the .pms reader.
#pragma once
#include <span>
#include <string>

#include "spm/vertex_id.h"

namespace pms::detail {

// Fills tree_id/node_id (sized like first_child) in array order: parents precede their children,
// so a node's id is final before its children's are derived from it (docs/internals.md, "Vertex ids").
// Throws pms::Error prefixed by `where` for a child index that breaks that order or a node
// deeper than 63 levels (its node-id would not fit 64 bits).
void compute_ids(uint32_t root_count, std::span<const uint32_t> first_child, std::span<uint32_t> tree_id,
                 std::span<uint64_t> node_id, const std::string& where);

// Node index of `id`, walking from its root along the node-id's bits below the leading 1;
// kNone when the tree does not exist or the path leaves the hierarchy. Never reads out of bounds.
uint32_t find_node(uint32_t root_count, std::span<const uint32_t> first_child, VertexId id);

}  // namespace pms::detail
