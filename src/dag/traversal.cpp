// MANAGE-TRAVERSAL and the three traversals of Zheng & Chan 2006 (§4 Fig. 2, §5 Figs. 3–5) over a DagCut.
//
// ERROR-EVALUATE is the refinement engine's qrefine (Hoppe 1997 §4) and its priority, on the DAG's decoded
// NodeCriteria. NEED-APPLY of a split candidate is qrefine; a candidate still waiting for a dependency
// is split together with what it needs (each of those split when it reaches Fs), as the adaptation loop's
// forced chain does. NEED-APPLY of an Fc node is "not qrefine" for the linear and constant-time traversals.
// The priority traversal first justifies the split nodes top down as the adaptation loop does (a split node
// is kept when its parent is kept and it qrefines, or when a kept node or a wanted candidate needs it), so
// that it collapses exactly what the view's target mesh does not hold: the criteria are not monotone, and
// with the local rule a node whose parent does not qrefine could keep that parent split forever.
#include "dag/traversal.h"

#include <algorithm>
#include <cmath>
#include <cstddef>

#include "common/error.h"
#include "spm/criteria_inline.h"

namespace pms {
namespace {
// Constant-time's watch list: a candidate is worth watching from this closeness on (its screen error half
// τ, or outside a plane by half the eye distance); the entries predicted to need a split take at most this
// share of a phase's evaluations (the sweep keeps the rest); a cut watches at most one node in this many.
constexpr float kWatchNear = 0.5f, kWatchShare = 0.5f;
constexpr uint32_t kNodesPerWatch = 320;
// and at most this many per evaluation a phase allows (N), so that the list's pass each frame stays O(N)
// however large the model.
constexpr uint32_t kWatchPerEvaluation = 16;
// Due entries whose node's criteria and state are fetched ahead of their evaluation.
constexpr size_t kDueLead = 8;
}  // namespace

uint32_t DagTraverser::watch_limit(uint32_t nodes, uint32_t max_ops) {
  const uint32_t limit = nodes / kNodesPerWatch;
  return max_ops ? uint32_t(std::min<uint64_t>(limit, uint64_t(kWatchPerEvaluation) * max_ops)) : limit;
}

DagTraverser::Scratch& DagTraverser::scratch() {
  static thread_local Scratch s;
  return s;
}

size_t DagTraverser::thread_scratch_bytes() {
  const Scratch& s = scratch();
  return (s.collapse_heap.capacity() + s.split_heap.capacity()) * sizeof(Ranked) + s.due.capacity() * sizeof(Due) +
         s.stack.capacity() * sizeof(uint64_t) + s.hot.capacity() * sizeof(uint32_t);
}

bool DagTraverser::qrefine(uint32_t n, DagFrameStats& stats) {
  ++stats.evaluated;
  return criteria_detail::qrefine_inline(view_, cut_->dag().criteria(n));
}

// Constant-time's watch list (DagCut::watch()). A candidate an evaluation found not needing a split is
// watched when it is in view below the threshold (kind 0, key: the eye distance to the DAG's centre at
// which its screen error is predicted to reach τ, the error growing as 1 / the distance), or above the
// threshold but outside a frustum plane (kind 1 + the plane, key: the plane's value at the node's sphere
// less its value at the DAG's centre; the planes move with the view, and the node is predicted inside that
// plane once the plane's value at the centre reaches -key). Closeness: 1 when predicted to need its split
// now, less the farther it is from that (in eye distances).
float DagTraverser::closeness(const DagCut::Watch& w) const {
  return w.key * inverse_distance_ + closeness_offset_[w.kind()];  // kind 0: 0; a plane's: 1 + its value at the centre
}

// `o` and `exceeds`: the node's eye offset and whether its screen error is over the threshold (its
// evaluation computed both already).
void DagTraverser::consider_watch(uint32_t n, const criteria_detail::EyeOffset& o, bool exceeds) {
  DagCut& cut = *cut_;
  if (cut.watched(n) || watch_limit_ == 0 || n >> 29) return;
  const NodeCriteria& c = cut.dag().criteria(n);
  // Below the threshold, the closeness is the screen ratio: most candidates the sweep meets are far below
  // the floor, and this leaves them before the culling tests (with a margin for the key's rounding).
  float ratio2 = 0;
  if (!exceeds) {
    ratio2 = criteria_detail::screen_ratio2_inline(view_, c, o);
    if (ratio2 < 0.99f * watch_floor_ * watch_floor_) return;
  }
  if (criteria_detail::back_facing_inline(c, o)) return;
  float outside = 0;
  int plane = -1;
  for (int k = 0; k < 6; ++k) {
    const float* pl = view_.planes[k];
    const float value = criteria_detail::dot3(pl, c.p) + pl[3] + c.radius;
    if (value < outside) outside = value, plane = k;
  }
  DagCut::Watch w;
  if (plane < 0) {
    if (exceeds) return;  // culled by the float slack alone
    w = {n, std::sqrt(std::min(ratio2, 1.0f)) * eye_distance_};
  } else {
    if (!exceeds) return;
    w = {n | uint32_t(plane + 1) << 29, outside - plane_at_centre_[plane]};
  }
  if (closeness(w) < watch_floor_) return;
  cut.watch().push_back(w);
  cut.set_watched(n, true);
}

// qrefine for constant-time's split phase (one ERROR-EVALUATE), watching the candidate when it does not.
bool DagTraverser::qrefine_watch(uint32_t n, DagFrameStats& stats) {
  ++stats.evaluated;
  const NodeCriteria& c = cut_->dag().criteria(n);
  const criteria_detail::EyeOffset o = criteria_detail::eye_offset(view_, c);
  const bool exceeds = criteria_detail::screen_error_exceeds_inline(view_, c, o);
  float lowest;
  if (exceeds && !criteria_detail::outside_frustum_inline(view_, c, o, lowest))  // qrefine_inline's tests, in its order
    return !criteria_detail::back_facing_inline(c, o);  // back-facing: never watched, so nothing more to do
  consider_watch(n, o, exceeds);
  return false;
}

// One pass over the list at the start of a split phase: the entries whose node is no candidate any more
// leave it, and so do the entries predicted to need their split now (at most `share`, the closest when
// more are due; the rest go back), taken in the list's order: a phase nearly always reaches all of them
// within its N, so ranking them bought a sort. The same pass sets the floor below which an entry is not
// worth its place (the closest three quarters of the limit stay above it), from every 4th entry kept.
void DagTraverser::prepare_watch(uint32_t share) {
  constexpr int kBuckets = 32;
  uint32_t histogram[kBuckets] = {};
  DagCut& cut = *cut_;
  std::vector<Due>& due = scratch().due;
  due.clear();
  std::vector<DagCut::Watch>& watch = cut.watch();
  const float scale = kBuckets / (1 - kWatchNear);
  size_t kept = 0;
  for (const DagCut::Watch w : watch) {
    const uint32_t n = w.node();
    if (!cut.is_candidate(n)) {
      cut.set_watched(n, false);
      continue;
    }
    const float c = closeness(w);
    if (c >= 1) {
      due.push_back({c, w});
      continue;
    }
    if (kept % 4 == 0) ++histogram[std::clamp(int((c - kWatchNear) * scale), 0, kBuckets - 1)];
    watch[kept++] = w;
  }
  watch.resize(kept);
  if (due.size() > share) {
    std::nth_element(due.begin(), due.begin() + share, due.end(),
                     [](const Due& a, const Due& b) { return a.closeness > b.closeness; });
    for (size_t i = share; i < due.size(); ++i) watch.push_back(due[i].entry);
    due.resize(share);
  }
  for (size_t k = 1; k <= kDueLead && k <= due.size(); ++k) cut.prefetch(due[due.size() - k].entry.node());
  watch_floor_ = kWatchNear;
  uint32_t above = 0;
  for (int b = kBuckets; b-- > 0;) {
    above += 4 * histogram[b];
    if (above > watch_limit_ * 3 / 4) {
      watch_floor_ = kWatchNear + float(b + 1) / scale;
      break;
    }
  }
}

uint32_t DagTraverser::pop_watch() {
  std::vector<Due>& due = scratch().due;
  while (!due.empty()) {
    const uint32_t n = due.back().entry.node();
    due.pop_back();
    if (due.size() >= kDueLead) cut_->prefetch(due[due.size() - kDueLead].entry.node());  // scattered
    cut_->set_watched(n, false);
    if (cut_->is_candidate(n)) return n;
  }
  return kNone;
}

// The due entries the phase did not reach go back; then, over the limit, the entries below the floor
// leave, and if still over it, the farthest. The order of the rest stays, so a stored and loaded list
// (CompactDagCut, which keeps only the candidates' entries) is the same list.
void DagTraverser::trim_watch() {
  DagCut& cut = *cut_;
  std::vector<DagCut::Watch>& watch = cut.watch();
  for (const Due& d : scratch().due) watch.push_back(d.entry);
  scratch().due.clear();
  if (watch.size() <= watch_limit_) return;
  size_t kept = 0;
  for (const DagCut::Watch& w : watch) {
    if (closeness(w) < watch_floor_) cut.set_watched(w.node(), false);
    else watch[kept++] = w;
  }
  watch.resize(kept);
  if (watch.size() <= watch_limit_) return;
  std::nth_element(watch.begin(), watch.begin() + watch_limit_, watch.end(),
                   [&](const DagCut::Watch& a, const DagCut::Watch& b) { return closeness(a) > closeness(b); });
  for (size_t i = watch_limit_; i < watch.size(); ++i) cut.set_watched(watch[i].node(), false);
  watch.resize(watch_limit_);
}

float DagTraverser::priority(uint32_t n, DagFrameStats& stats) {
  ++stats.evaluated;
  return criteria_detail::priority_inline(view_, cut_->dag().criteria(n));
}

// Top down from the roots (the adaptation loop's walk over the cut): marks the split nodes the view keeps
// and the collapsed ones a wanted candidate needs. Each node is evaluated at most once; the wanted
// candidates go straight to the split heap (a candidate below an unkept parent is never wanted, and the
// collapse phase only makes such candidates).
void DagTraverser::justify(DagFrameStats& stats) {
  DagCut& cut = *cut_;
  const Dag& dag = cut.dag();
  cut.clear_marks();
  scratch().split_heap.clear();
  std::vector<uint64_t>& stack = scratch().stack;
  stack.clear();
  for (uint32_t r : dag.roots()) stack.push_back(uint64_t(r) << 1);
  while (!stack.empty()) {
    const uint64_t entry = stack.back();
    stack.pop_back();
    const uint32_t v = uint32_t(entry >> 1);
    if (cut.marked(v)) continue;
    if (entry & 1) {
      cut.mark(v);  // needed by a kept node or a wanted candidate
    } else if (cut.is_split(v)) {
      if (!qrefine(v, stats)) continue;  // it may still be forced later
      cut.mark(v);
    } else {
      const float key = priority(v, stats);
      if (key <= 0) {
        if (seed_watch_) {
          const criteria_detail::EyeOffset o = criteria_detail::eye_offset(view_, dag.criteria(v));
          consider_watch(v, o, criteria_detail::screen_error_exceeds_inline(view_, dag.criteria(v), o));
        }
        continue;
      }
      push_split(key, v);
    }
    if (cut.is_split(v))
      for (int k = 0; k < 2; ++k)
        if (const uint32_t c = dag.hierarchy_child(v, k); c != kNone) stack.push_back(uint64_t(c) << 1);
    for (uint32_t p : dag.parents(v)) stack.push_back(uint64_t(p) << 1 | 1);
  }
}

void DagTraverser::push_split(float key, uint32_t n) {
  std::vector<Ranked>& heap = scratch().split_heap;
  heap.push_back({key, n});
  std::push_heap(heap.begin(), heap.end(), [](const Ranked& a, const Ranked& b) { return a.key < b.key; });
}

void DagTraverser::push_split_candidate(uint32_t n, DagFrameStats& stats) {
  const uint32_t p = cut_->dag().hierarchy_parent(n);
  if (p != kNone && !cut_->marked(p)) return;  // its parent leaves the target mesh: not wanted
  if (const float key = priority(n, stats); key > 0) push_split(key, n);
}

// Splits n after the collapsed nodes it needs, each one as it reaches Fs. False when a limit stopped it
// (the splits done so far stay: each was legal).
bool DagTraverser::split_with_needs(uint32_t n, Limits& limits, DagFrameStats& stats, std::vector<DagOp>& ops) {
  DagCut& cut = *cut_;
  const Dag& dag = cut.dag();
  while (!cut.is_split(n)) {
    uint32_t y = n;
    while (!cut.in_fs(y)) {  // a collapsed node with a collapsed DAG parent: climb to one
      for (uint32_t p : dag.parents(y))
        if (!cut.is_split(p)) {
          y = p;
          break;
        }
    }
    if (limits.max_ops && stats.splits >= limits.max_ops) return false;
    if (dag.faces(y) > limits.room) {
      stats.stopped_by_budget = true;
      return false;
    }
    if (limits.room != UINT64_MAX) limits.room -= dag.faces(y);
    cut.split(y);
    ops.push_back({y, true});
    ++stats.splits;
    stats.forced += y != n;
    if (justified_) {
      cut.mark(y);
      for (int k = 0; k < 2; ++k)
        if (const uint32_t c = dag.hierarchy_child(y, k); c != kNone) push_split_candidate(c, stats);
    }
  }
  return true;
}

void DagTraverser::collapse(uint32_t n, DagFrameStats& stats, std::vector<DagOp>& ops) {
  cut_->collapse(n);
  ops.push_back({n, false});
  ++stats.collapses;
}

// Fig. 3 over Fc: the least visible errors first. Only the unkept nodes need applying, so only they are
// evaluated for their priority.
void DagTraverser::priority_collapse(const Limits& limits, DagFrameStats& stats, std::vector<DagOp>& ops) {
  DagCut& cut = *cut_;
  std::vector<Ranked>& heap = scratch().collapse_heap;
  const auto later = [](const Ranked& a, const Ranked& b) { return a.key > b.key; };
  const auto push = [&](uint32_t n) {
    if (cut.marked(n)) return;  // kept: NEED-APPLY fails
    heap.push_back({priority(n, stats), n});
    std::push_heap(heap.begin(), heap.end(), later);
  };
  heap.clear();
  for (uint32_t n = cut.next_fc(0); n != kNone; n = cut.next_fc(n + 1)) push(n);
  while (!heap.empty() && !(limits.max_ops && stats.collapses >= limits.max_ops)) {
    std::pop_heap(heap.begin(), heap.end(), later);
    const uint32_t n = heap.back().node;
    heap.pop_back();
    if (!cut.in_fc(n)) continue;
    collapse(n, stats, ops);
    for (uint32_t p : cut.dag().parents(n))
      if (cut.in_fc(p)) push(p);
  }
}

// Fig. 3 over the split candidates, the most visible errors first: the heap justify() filled, and the
// children of what it splits.
void DagTraverser::priority_split(Limits& limits, DagFrameStats& stats, std::vector<DagOp>& ops) {
  DagCut& cut = *cut_;
  std::vector<Ranked>& heap = scratch().split_heap;
  const auto less = [](const Ranked& a, const Ranked& b) { return a.key < b.key; };
  while (!heap.empty()) {
    std::pop_heap(heap.begin(), heap.end(), less);
    const uint32_t n = heap.back().node;
    heap.pop_back();
    if (!cut.is_candidate(n)) continue;  // split meanwhile, for a node that needed it
    if (!split_with_needs(n, limits, stats, ops)) return;
  }
}

// Figs. 4 and 5, with the cut's sweeps in node order for the paper's FIFO queues (a session keeps two
// cursors between frames, not the queues: docs/internals.md, "Per-session memory"). A node that does not
// need applying stays in its front, met again on the next lap. A phase stops at the operation or evaluation
// limit, at an empty front, or at the first node it already evaluated (a whole lap without anything left to
// apply, Fig. 4 line 11: NEED-APPLY depends only on the view, so a second look would say the same); the
// sweep is rewound to that node. Each node is evaluated at most once a phase from the sweep.
// With `hot` (constant-time), the front nodes the phase's own operations made are evaluated first, last made
// first: where the view wanted a change, the next level of the same region most likely wants one too, and
// behind a front of tens of thousands of nodes at N a call the sweep would reach it only frames later.
template <class Live, class Predicted, class Pop, class Rewind, class TryApply>
void DagTraverser::fifo_phase(const uint32_t& applied, const Limits& limits, DagFrameStats& stats,
                              std::vector<uint32_t>* hot, Live live, Predicted predicted, Pop pop, Rewind rewind,
                              TryApply try_apply) {
  DagCut& cut = *cut_;
  const uint32_t evaluated_before = stats.evaluated;
  if (hot) hot->clear();  // a phase's own: the nodes left are in their front
  while (!(limits.max_ops && applied >= limits.max_ops) &&
         !(limits.max_evaluated && stats.evaluated - evaluated_before >= limits.max_evaluated)) {
    uint32_t n = kNone;
    while (hot && !hot->empty() && n == kNone) {
      n = hot->back();
      hot->pop_back();
      if (!live(n)) n = kNone;
    }
    if (n == kNone) n = predicted();
    const bool from_hot = n != kNone;  // or from the watch list: not the sweep's
    if (!from_hot) {
      n = pop();
      if (n == kNone) break;
      if (cut.marked(n)) {
        rewind(n);
        break;
      }
    }
    const Outcome outcome = try_apply(n);
    if (outcome == Outcome::stopped) break;
    if (outcome == Outcome::not_needed && !from_hot) cut.mark(n);
  }
  cut.clear_marks();
}

void DagTraverser::fifo_collapse(const Limits& limits, DagFrameStats& stats, std::vector<DagOp>& ops,
                                 std::vector<uint32_t>* hot) {
  DagCut& cut = *cut_;
  fifo_phase(
      stats.collapses, limits, stats, hot, [&](uint32_t n) { return cut.in_fc(n); }, [] { return kNone; },
      [&] { return cut.pop_collapse(); }, [&](uint32_t n) { cut.rewind_collapse(n); },
      [&](uint32_t n) {
        if (qrefine(n, stats)) return Outcome::not_needed;
        collapse(n, stats, ops);
        if (hot)
          for (uint32_t p : cut.dag().parents(n))
            if (cut.in_fc(p)) {
              hot->push_back(p);
              cut.prefetch(p);
            }
        return Outcome::applied;
      });
}

void DagTraverser::fifo_split(Limits& limits, DagFrameStats& stats, std::vector<DagOp>& ops,
                              std::vector<uint32_t>* hot) {
  DagCut& cut = *cut_;
  const Dag& dag = cut.dag();
  if (hot) prepare_watch(uint32_t(kWatchShare * float(limits.max_evaluated)));
  fifo_phase(
      stats.splits, limits, stats, hot, [&](uint32_t n) { return cut.is_candidate(n); },
      [&] { return hot ? pop_watch() : kNone; }, [&] { return cut.pop_split(); },
      [&](uint32_t n) { cut.rewind_split(n); },
      [&](uint32_t n) {
        if (!(hot ? qrefine_watch(n, stats) : qrefine(n, stats))) return Outcome::not_needed;
        const size_t first = ops.size();
        const bool done = split_with_needs(n, limits, stats, ops);
        if (hot)
          for (size_t i = first; i < ops.size(); ++i)
            for (int k = 0; k < 2; ++k)
              if (const uint32_t c = dag.hierarchy_child(ops[i].node, k); c != kNone && cut.is_candidate(c)) {
                hot->push_back(c);
                cut.prefetch(c);
              }
        if (done) return Outcome::applied;
        if (cut.is_candidate(n)) cut.rewind_split(n);  // a limit stopped it, maybe halfway: first next time
        return Outcome::stopped;
      });
  if (hot) trim_watch();
}

// Fig. 2. In BUDGET mode the splits' triangles are limited to what keeps the cut within the budget.
DagFrameStats DagTraverser::manage(const DagManageOptions& options, std::vector<DagOp>& ops) {
  if (!has_view_) fail("dag traversal", "no view set");
  {
    const float* c = cut_->dag().centre();
    float d2 = 0;
    for (int k = 0; k < 3; ++k) d2 += (view_.eye[k] - c[k]) * (view_.eye[k] - c[k]);
    eye_distance_ = std::max(std::sqrt(d2), 1e-30f);
    inverse_distance_ = 1 / eye_distance_;
    closeness_offset_[0] = 0;
    watch_limit_ = watch_limit(cut_->dag().size(), options.max_ops);
    watch_floor_ = kWatchNear;
    for (int k = 0; k < 6; ++k) {
      const float* pl = view_.planes[k];
      plane_at_centre_[k] = pl[0] * c[0] + pl[1] * c[1] + pl[2] * c[2] + pl[3];
      closeness_offset_[k + 1] = 1 + plane_at_centre_[k] * inverse_distance_;
    }
  }
  DagFrameStats stats;
  Limits limits;
  const bool constant_time = options.traversal == DagTraversal::constant_time;
  if (constant_time) limits.max_evaluated = options.max_ops;
  else limits.max_ops = options.max_ops;
  justified_ = options.traversal == DagTraversal::priority;
  if (justified_) justify(stats);
  if (justified_) priority_collapse(limits, stats, ops);
  else fifo_collapse(limits, stats, ops, constant_time ? &scratch().hot : nullptr);
  if (options.mode == DagMode::budget) {
    const uint64_t t = cut_->triangles();
    limits.room = options.budget > t ? options.budget - t : 0;
  }
  if (justified_) priority_split(limits, stats, ops);
  else fifo_split(limits, stats, ops, constant_time ? &scratch().hot : nullptr);
  if (justified_) cut_->clear_marks();
  justified_ = false;
  return stats;
}

DagFrameStats DagTraverser::converge(const DagManageOptions& options, std::vector<DagOp>& ops, uint32_t max_ops) {
  DagManageOptions unlimited = options;
  unlimited.traversal = DagTraversal::priority;
  seed_watch_ = options.traversal == DagTraversal::constant_time;
  const size_t start = ops.size();
  DagFrameStats total;
  // Each round but the last changes the cut; the bound only guards against a cycle no test has found.
  for (int round = 0; round < 64; ++round) {
    const size_t before = ops.size();
    if (max_ops && before - start >= max_ops) break;
    unlimited.max_ops = max_ops ? uint32_t(max_ops - (before - start)) : 0;
    const DagFrameStats stats = manage(unlimited, ops);
    total.splits += stats.splits;
    total.collapses += stats.collapses;
    total.forced += stats.forced;
    total.evaluated += stats.evaluated;
    total.stopped_by_budget |= stats.stopped_by_budget;
    if (ops.size() == before) break;
  }
  if (seed_watch_) trim_watch();
  seed_watch_ = false;
  return total;
}

}  // namespace pms
