// Traversals of a DAG cut (Zheng & Chan 2006 §4–5): MANAGE-TRAVERSAL(vp, mode, N) collapses first, then
// splits, under the fidelity constraint (the view and τ, evaluated by the refinement engine's own qrefine on
// the same decoded numbers), the mesh-change constraint N and, in BUDGET mode, the client's triangle budget.
// Three algorithms: priority-oriented (every front node evaluated, two priority queues), linear (the cut's
// sweeps of its fronts, continued from frame to frame, at most N operations) and constant-time (at most N nodes
// evaluated, the front nodes its own operations made first). docs/internals.md ("The DAG of operations") has
// the rules and why priority converges to the adaptation loop's mesh.
// Shared with the browser build: single-threaded, no std::ranges algorithms, std::format or coroutines.
#pragma once
#include <cstdint>
#include <vector>

#include "dag/cut.h"
#include "spm/criteria.h"

namespace pms {
namespace criteria_detail {
struct EyeOffset;
}

enum class DagTraversal : uint8_t { priority, linear, constant_time };
enum class DagMode : uint8_t { free, budget };

struct DagManageOptions {
  DagTraversal traversal = DagTraversal::priority;
  DagMode mode = DagMode::free;
  // N: operations per phase (priority, linear) or nodes evaluated per phase (constant-time); 0 = no limit.
  uint32_t max_ops = 300;
  // BUDGET mode: the splits add at most as many triangles as keep the cut at or below this (so, from a cut
  // within the budget, at least as many as the collapses removed: the paper's rule counted in triangles).
  uint64_t budget = 0;
};

struct DagOp {
  uint32_t node;  // DAG node
  bool split;     // false: collapse
};

struct DagFrameStats {
  uint32_t splits = 0, collapses = 0;
  uint32_t forced = 0;     // of the splits, those a wanted node needed first
  uint32_t evaluated = 0;  // ERROR-EVALUATE calls
  bool stopped_by_budget = false;
};

class DagTraverser {
 public:
  explicit DagTraverser(DagCut& cut) : cut_(&cut) {}

  void set_view(const ViewCriteria& view) {
    view_ = view;
    has_view_ = true;
  }
  // MANAGE-TRAVERSAL (Fig. 2): applies the operations to the cut and appends them to `ops` in that order.
  // pms::Error before set_view().
  DagFrameStats manage(const DagManageOptions& options, std::vector<DagOp>& ops);
  // The cut converged for the view within options' mode and budget: the priority traversal without an
  // operation limit, repeated until a round makes no operation (a DAG session's first answer; its traversal
  // and N only apply from the second view on). Stats summed over the rounds. At most `max_ops` operations
  // (0: no limit): a server bounds a first answer as it bounds any other.
  DagFrameStats converge(const DagManageOptions& options, std::vector<DagOp>& ops, uint32_t max_ops = 0);

  DagCut& cut() { return *cut_; }
  // Between frames a traverser holds nothing beyond the cut and the view. The calling thread's scratch,
  // shared by every traverser manage() runs on it (the priority traversal's heaps and justification stack,
  // constant-time's hot nodes): a server has a few I/O threads and many sessions.
  static size_t thread_scratch_bytes();
  // Constant-time's watch list holds at most this many entries (DagCut::watch()) for a DAG of `nodes` and N.
  static uint32_t watch_limit(uint32_t nodes, uint32_t max_ops);

 private:
  struct Limits {
    uint32_t max_ops = 0, max_evaluated = 0;  // 0 = none
    uint64_t room = UINT64_MAX;               // triangles the splits may add
  };
  struct Ranked {
    float key;
    uint32_t node;
  };
  struct Due {
    float closeness;
    DagCut::Watch entry;
  };
  bool qrefine(uint32_t n, DagFrameStats& stats);
  float priority(uint32_t n, DagFrameStats& stats);
  void justify(DagFrameStats& stats);
  void force_closure(uint32_t n);
  bool split_with_needs(uint32_t n, Limits& limits, DagFrameStats& stats, std::vector<DagOp>& ops);
  void collapse(uint32_t n, DagFrameStats& stats, std::vector<DagOp>& ops);
  void priority_collapse(const Limits& limits, DagFrameStats& stats, std::vector<DagOp>& ops);
  void priority_split(Limits& limits, DagFrameStats& stats, std::vector<DagOp>& ops);
  void push_split(float key, uint32_t n);
  void push_split_candidate(uint32_t n, DagFrameStats& stats);
  enum class Outcome { not_needed, applied, stopped };
  template <class Live, class Predicted, class Pop, class Rewind, class TryApply>
  void fifo_phase(const uint32_t& applied, const Limits& limits, DagFrameStats& stats, std::vector<uint32_t>* hot,
                  Live live, Predicted predicted, Pop pop, Rewind rewind, TryApply try_apply);
  bool qrefine_watch(uint32_t n, DagFrameStats& stats);
  float closeness(const DagCut::Watch& w) const;
  void consider_watch(uint32_t n, const criteria_detail::EyeOffset& o, bool exceeds);
  void prepare_watch(uint32_t share);
  uint32_t pop_watch();
  void trim_watch();
  void fifo_collapse(const Limits& limits, DagFrameStats& stats, std::vector<DagOp>& ops, std::vector<uint32_t>* hot);
  void fifo_split(Limits& limits, DagFrameStats& stats, std::vector<DagOp>& ops, std::vector<uint32_t>* hot);

  DagCut* cut_;
  ViewCriteria view_;
  bool has_view_ = false;
  bool justified_ = false;                         // priority: marks say which split nodes the view's target mesh keeps
  float eye_distance_ = 1, inverse_distance_ = 1;  // to the DAG's centre
  float watch_floor_ = 0;
  uint32_t watch_limit_ = 0;
  float plane_at_centre_[6] = {};
  float closeness_offset_[8] = {};
  bool seed_watch_ = false;
  struct Scratch {
    std::vector<Ranked> collapse_heap, split_heap;
    std::vector<uint64_t> stack;  // node << 1 | forced
    std::vector<uint32_t> hot;    // constant-time: the front nodes the phase's own operations made
    std::vector<Due> due;         // constant-time: the watch entries predicted to need a split now
  };
  static Scratch& scratch();
};

}  // namespace pms
