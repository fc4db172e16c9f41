// Resolving a receiver-driven request to model nodes: bounded by the answer's size before it is built.
#include <string>

#include "protocol/message_types.h"
#include "server/split_lookup.h"
#include "spm/vertex_id.h"

namespace pms::server {

using protocol::ErrorCode;
using protocol::ProtocolError;

std::vector<uint32_t> requested_nodes(const ModelData& model, const protocol::SplitRequest& request,
                                      uint32_t max_splits) {
  std::vector<uint32_t> nodes;
  nodes.reserve(request.ids.size());
  const auto add = [&](uint32_t n) {
    if (nodes.size() >= max_splits)
      throw ProtocolError(ErrorCode::too_large, "the answer would carry more than " + std::to_string(max_splits) +
                                                    " splits: ask for fewer ids or a smaller depth");
    nodes.push_back(n);
  };
  for (VertexId id : request.ids) {
    const uint32_t node = id.tree < model.root_count ? model.find(id) : kNone;
    if (node == kNone) throw ProtocolError(ErrorCode::bad_id, to_string(id) + " is not a vertex of the model");
    if (model.is_leaf(node))
      throw ProtocolError(ErrorCode::bad_id, to_string(id) + " has no split (a leaf of the model)");
    // Breadth-first, one level at a time: nodes[level_begin, end) is the level being expanded.
    size_t level_begin = nodes.size();
    add(node);
    for (uint32_t level = 0; level < request.depth; ++level) {
      const size_t level_end = nodes.size();
      for (size_t i = level_begin; i < level_end; ++i)
        for (uint32_t c = 0; c < 2; ++c)
          if (const uint32_t child = model.first_child[nodes[i]] + c; !model.is_leaf(child)) add(child);
      level_begin = level_end;
    }
  }
  return nodes;
}

}  // namespace pms::server
