// SelectiveStreaming / SelStreamVSplit (kim-lee-kobbelt §5.3, §6.1): which vsplit packets a VIEW
// needs, decided on the server from the session's active tags alone (no mesh). The front is walked
// most important first (a max-heap on the screen-space error), so a slow link delivers the most
// useful splits first; a split whose fundamental cut vertices share an active ancestor first sends
// that ancestor's split (the partial order the client's SelVSplit will need).
#pragma once
#include <cstdint>
#include <functional>
#include <vector>

#include "pm/pm.h"
#include "server/active_tags.h"

namespace pms {

// importance(node) > 0 when qrefine(node) holds for the view; larger = more visible error.
using Importance = std::function<float(uint32_t node)>;

struct StreamingScratch {
  std::vector<std::pair<float, uint32_t>> heap;
  std::vector<uint32_t> stack;
};

// Appends to `out` the internal nodes to split, each after every split it depends on, and updates
// `tags` as if they were sent. Stops after `max_splits` (the rest waits for the next VIEW).
// Returns whether the view is fully served (nothing left that qrefine wants).
bool selective_streaming(const ModelView& model, ActiveTags& tags, const Importance& importance, size_t max_splits,
                         std::vector<uint32_t>& out, StreamingScratch& scratch);

// ActiveAncestor (kim-lee-kobbelt §4) on the server: walk up from `node` to the active node.
uint32_t active_ancestor(const ModelView& model, const ActiveTags& tags, uint32_t node);

}  // namespace pms
