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

// Where ActiveAncestor starts climbing for a split's fundamental cut vertices: the cut vertex's ancestors
// one level below the node being split and at its level. The cut vertices are leaves, ~6 levels below
// the active node they stand for, and in a model of a million nodes every level is a cache miss; the
// front is rarely more than a level or two from the split node's (dragon: 62 % at these two levels, 91 %
// within two levels). Built once per model, shared by its sessions: 16 bytes per internal node, one
// aligned block with both sides' starts.
class ClimbStarts {
 public:
  static constexpr int kLevels = 2;  // per side: the ancestor below v's level, then its parent
  ClimbStarts() = default;           // no starts: every climb begins at the cut vertex itself
  explicit ClimbStarts(const ModelView& model);
  // kLevels ancestors-or-self of the `side` (0 left, 1 right) cut vertex of internal `node`, nearest the
  // cut first; nullptr when there are no starts or no such cut vertex.
  const uint32_t* of(const ModelView& model, uint32_t node, int side) const {
    const uint32_t cut = side == 0 ? model.cut_left[node] : model.cut_right[node];
    if (starts_.empty() || cut == kNone) return nullptr;
    // Children come in adjacent pairs tiling [root_count, node_count) (pms_validate), so a split node's
    // first child numbers the internal nodes densely.
    return &starts_[(size_t(model.first_child[node]) - model.root_count) * kLevels + size_t(side) * kLevels];
  }
  size_t memory_bytes() const { return starts_.capacity() * sizeof(uint32_t); }

 private:
  std::vector<uint32_t> starts_;
};

// importance(node) > 0 when qrefine(node) holds for the view; larger = more visible error.
using Importance = std::function<float(uint32_t node)>;

// One VIEW's answer, produced in batches so a session holds encoded bytes for one batch at a time:
// start() ranks the front once; each step() hands out the next most important splits.
class SelectiveStreamer {
 public:
  void start(const ModelView& model, const ClimbStarts& starts, ActiveTags& tags, Importance importance);
  // Appends up to `max_splits` nodes to split to `out`, each after every split it depends on, and
  // updates the tags as if they were sent. Returns true once the view is fully served.
  bool step(size_t max_splits, std::vector<uint32_t>& out);
  bool active() const { return model_ != nullptr; }
  // Frees the ranking (a served view keeps no memory in the session).
  void stop();

 private:
  const ModelView* model_ = nullptr;
  const ClimbStarts* starts_ = nullptr;
  ActiveTags* tags_ = nullptr;
  Importance importance_;
  std::vector<std::pair<float, uint32_t>> heap_;
  std::vector<uint32_t> stack_;
};

// The whole answer at once (tests and tools): returns whether the view is served within max_splits.
bool selective_streaming(const ModelView& model, const ClimbStarts& starts, ActiveTags& tags,
                         const Importance& importance, size_t max_splits, std::vector<uint32_t>& out);

// ActiveAncestor (kim-lee-kobbelt §4) on the server: the active node on the path from `leaf` to its root.
// `starts` (ClimbStarts::of, or nullptr) are tried first, then a climb from above them runs beside the one
// from the leaf; whichever meets the front first answers.
uint32_t active_ancestor(const ModelView& model, const ActiveTags& tags, uint32_t leaf, const uint32_t* starts);

}  // namespace pms
