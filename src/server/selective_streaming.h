// SelectiveStreaming / SelStreamVSplit (kim-lee-kobbelt §5.3, §6.1): which vsplit packets a VIEW
// needs, decided on the server from the session's active tags alone (no mesh). The front is walked
// most important first (a max-heap on the screen-space error), so a slow link delivers the most
// useful splits first; a split whose fundamental cut vertices share an active ancestor first sends
// that ancestor's split (the partial order the client's SelVSplit will need).
#pragma once
#include <cstdint>
#include <functional>
#include <vector>

#include "server/active_tags.h"
#include "server/phase_times.h"
#include "spm/dependency_filter.h"
#include "spm/hierarchy.h"

namespace pms {

// importance(node) > 0 when qrefine(node) holds for the view; larger = more visible error.
using Importance = std::function<float(uint32_t node)>;

// The cut vertices a split has on the client's mesh when it is made (kim-lee-kobbelt §6.3): the active
// ancestors of its fundamental v̂_l, v̂_r, as node indices; kNone for a missing side.
struct ActualCuts {
  uint32_t left = kNone, right = kNone;
};

// One VIEW's answer, produced in slices so a session holds encoded bytes for one batch at a time and never
// keeps an I/O thread long: start() only records the view; each step() continues ranking the front (a
// scan that may take many steps on a large front) or hands out the next most important splits, within a
// work budget. The ranking is bounded (kMaxRanked nodes, 8 KB) so a session's memory stays its tags plus a
// few KB whatever the view: a child that finds it full waits for the next scan of the front, made when the
// ranking runs dry.
class SelectiveStreamer {
 public:
  static constexpr size_t kMaxRanked = 1024;

  // With `phases`, the ranking's time counts as determine_visibility and the splits' as update_front.
  void start(const ModelData& model, const DependencyFilter& dependencies, ActiveTags& tags, Importance importance,
             server::PhaseTimes* phases = nullptr);
  // Appends up to `max_splits` nodes to split to `out`, each after every split it depends on, and updates
  // the tags as if they were sent. Stops once `work` (nodes evaluated + split, added to) has grown by
  // `budget`, finishing the dependency chain in hand. Returns true once the view is fully served.
  // With `cuts`, each split's ActualCuts go there too, one per node appended to `out`, read off the tags
  // just before that split (the client's front when it applies the packets in order).
  bool step(size_t max_splits, uint64_t budget, std::vector<uint32_t>& out, uint64_t& work,
            std::vector<ActualCuts>* cuts = nullptr);
  bool active() const { return model_ != nullptr; }
  // Frees the ranking (a served view keeps no memory in the session).
  void stop();
  size_t memory_bytes() const { return heap_.capacity() * sizeof(heap_[0]) + stack_.capacity() * sizeof(uint32_t); }

 private:
  static constexpr uint32_t kNotScanning = UINT32_MAX;
  const ModelData* model_ = nullptr;
  const DependencyFilter* dependencies_ = nullptr;
  ActiveTags* tags_ = nullptr;
  Importance importance_;
  server::PhaseTimes* phases_ = nullptr;
  // Ranks the front from scan_ on: its kMaxRanked most important wanted nodes. Returns false when the
  // budget ran out first (the scan goes on at the next call).
  bool continue_scan(uint64_t budget, uint64_t& work);
  void begin_scan();
  // Ranks `node` if there is room; otherwise it waits for the next scan.
  void rank(uint32_t node, float importance);

  std::vector<std::pair<float, uint32_t>> heap_;  // while scanning a min-heap, then a max-heap; <= kMaxRanked
  bool overflow_ = false;                         // a wanted node is in neither the heap nor done
  uint32_t scan_ = kNotScanning;                  // the next front node to rank while scanning
  std::vector<uint32_t> stack_;
};

// The whole answer at once (tests and tools): returns whether the view is served within max_splits.
bool selective_streaming(const ModelData& model, const DependencyFilter& dependencies, ActiveTags& tags,
                         const Importance& importance, size_t max_splits, std::vector<uint32_t>& out);

// ActiveAncestor (kim-lee-kobbelt §4) on the server: walk up from `node` to the active node; kNone when
// none is (the tags are then not a front of the whole forest).
uint32_t active_ancestor(const ModelData& model, const ActiveTags& tags, uint32_t node);

}  // namespace pms
