// The adaptation loop: Hoppe 1997 §5 (traversal of the active front, vsplit where qrefine, ecol where not,
// geomorphs) and kim-lee-kobbelt 2005 §5.3 (SelectiveRefinement over a partial hierarchy: a known leaf
// that wants to split makes the client ask for its packet; SelStreamVSplit's partial order).
//
// The target mesh of a view is the least fixed point S: the smallest set of split nodes that holds every
// root with qrefine, every node with qrefine whose parent is in S, and, for every node in S, the node its
// split depends on (the deepest common ancestor of its cut vertices v̂_l, v̂_r, which must be split so that
// ActiveAncestor(v̂_l) != ActiveAncestor(v̂_r)) with all that node's ancestors. Because the criteria are
// not monotone (a child nearer the eye may pass the screen-space test while its parent fails it), Hoppe's
// local rule "collapse the parent when it does not qrefine" can leave nodes outside S split forever once a
// view moves away. So each frame re-derives which split nodes are wanted, top down, and collapses every
// other: from any mesh the loop settles on S, whatever the order packets arrived in or the op cap.
#include "spm/adapt.h"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstring>

#include "common/error.h"
#include "spm/criteria_inline.h"
#include "spm/hierarchy.h"
#include "spm/refine_info.h"
#include "spm/selective_mesh.h"
#include "spm/slot_growth.h"
#include "spm/split_record.h"
#include "spm/vertex_hierarchy.h"
#include "spm/vertex_id.h"

namespace pms {
namespace {

constexpr const char* kWhere = "selective refinement";
constexpr uint32_t kUnknown = kNone - 1;  // Slot::dependency not computed yet (slots stay below kNone - 2)
constexpr uint32_t kMaxSlots = 1u << 31;  // stack entries tag a slot with one bit
// Rounding bounds for walk_qrefine's plane bounds: a plane value ((a·x + b·y) + c·z) + d in float is
// within 4 units in the last place (2^-22) of |a·x| + |b·y| + |c·z| + |d| of the exact value; 2^-18 of
// the largest such sum is a 16x margin that also covers the subtractions that carry a bound down. A
// float distance is within a few units in the last place of the exact one; 2^-16 rounds it up.
constexpr float kPlaneRounding = 0x1p-18f, kReachRoundUp = 1 + 0x1p-16f, kTinyBound = 1e-30f;

// A stamp no earlier refinement in the process had (0 marks slots no one loaded). After 2^32 - 1
// refinements stamps repeat; a slot array would then have to reach one that old.
uint32_t new_stamp() {
  static std::atomic<uint32_t> last{0};
  uint32_t stamp = last.fetch_add(1, std::memory_order_relaxed) + 1;
  while (stamp == 0) stamp = last.fetch_add(1, std::memory_order_relaxed) + 1;
  return stamp;
}

}  // namespace

SelectiveRefinement::SelectiveRefinement(SelectiveMesh& mesh, float model_scale, const AdaptOptions& options)
    : mesh_(&mesh),
      scale_(dequantize_detail::effective_scale(model_scale)),
      stamp_(new_stamp()),
      synced_(mesh.hierarchy().size()) {
  static_assert(sizeof(Slot) == 64);
  // The roots' common parent for walk_qrefine's bounds: the mean of their positions (any point would
  // do; a central one lets a view that holds the whole model skip the roots' planes too).
  const VertexHierarchy& h = mesh.hierarchy();
  for (uint32_t r = 0; r < h.root_count(); ++r)
    for (int k = 0; k < 3; ++k) root_centre_[k] += h.position(h.root_slot(r))[k];
  for (int k = 0; k < 3; ++k) {
    root_centre_[k] /= float(std::max(h.root_count(), 1u));
    coordinate_bound_ = std::max(coordinate_bound_, std::fabs(root_centre_[k]));
  }
  set_options(options);
}

void SelectiveRefinement::set_options(const AdaptOptions& options) {
  if (!(options.tolerance >= 0) || !std::isfinite(options.tolerance))
    fail(kWhere, "tolerance must be a finite number >= 0");
  if (options.morph_frames != options_.morph_frames || options.max_ops != options_.max_ops ||
      options.time_budget_us != options_.time_budget_us)
    settled_ = false;
  options_ = options;
  morphs_.set_frames(options.morph_frames);
  if (has_view_) use_criteria(make_criteria(view_params_, options_.tolerance));
}

void SelectiveRefinement::set_view(const ViewParams& view) {
  view_params_ = view;
  use_criteria(make_criteria(view, options_.tolerance));
  has_view_ = true;
}

// Only what qrefine reads decides the walk: the same bytes give the same frame.
void SelectiveRefinement::use_criteria(const ViewCriteria& criteria) {
  static_assert(sizeof(ViewCriteria) == 28 * sizeof(float), "compared as bytes: no padding");
  if (std::memcmp(&criteria, &view_, sizeof view_) != 0) {
    settled_ = false;
    view_moved_ = true;
  }
  view_ = criteria;
  update_plane_bounds();
}

void SelectiveRefinement::update_plane_bounds() {
  float normal = 0, terms = 0;
  for (const float* plane : view_.planes) {
    normal = std::max(normal, std::sqrt(plane[0] * plane[0] + plane[1] * plane[1] + plane[2] * plane[2]));
    terms = std::max(terms, (std::fabs(plane[0]) + std::fabs(plane[1]) + std::fabs(plane[2])) * coordinate_bound_ +
                                std::fabs(plane[3]));
  }
  reach_scale_ = normal * kReachRoundUp;
  plane_error_ = terms * kPlaneRounding + kTinyBound;
  float lowest = INFINITY;
  for (const float* plane : view_.planes)
    lowest = std::min(lowest, criteria_detail::dot3(plane, root_centre_) + plane[3]);
  root_margin_ = lowest - plane_error_;
}

// A split arriving for a slot already decoded: children come as a pair after their parent, and the
// first of the pair tells the parent.
void SelectiveRefinement::sync() {
  const VertexHierarchy& h = mesh_->hierarchy();
  if (h.size() > kMaxSlots) fail(kWhere, "too many slots");
  if (morphs_.enabled()) morphs_.sync(*mesh_);
  for (uint32_t v = synced_; v < h.size(); ++v) {
    const uint32_t p = h.parent(v);
    if (p != kNone && p < slot_count_ && slots_[p].stamp == stamp_ && h.first_child(p) == v) slots_[p].first_child = v;
  }
  synced_ = h.size();
}

void SelectiveRefinement::grow(uint32_t end) {
  const size_t known = mesh_->hierarchy().size();
  if (end > known) fail(kWhere, "unknown slot");
  slots_.grow(end, known);
  slot_count_ = uint32_t(std::min<size_t>(slots_.size(), kMaxSlots));
}

void SelectiveRefinement::load(uint32_t v) {
  const VertexHierarchy& h = mesh_->hierarchy();
  Slot& slot = slots_[v];
  const float* p = h.position(v);
  slot.criteria = criteria_detail::node_criteria_inline(p, h.refine(v), scale_);
  slot.first_child = h.first_child(v);
  {
    const uint32_t parent = h.parent(v);
    const float* q = parent != kNone ? h.position(parent) : root_centre_;
    const float d[3] = {p[0] - q[0], p[1] - q[1], p[2] - q[2]};
    slot.reach = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) * kReachRoundUp + kTinyBound;
  }
  slot.kept = 0;
  slot.dependency = kUnknown;
  slot.stamp = stamp_;
  const float extent = std::max({std::fabs(p[0]), std::fabs(p[1]), std::fabs(p[2])});
  if (extent > coordinate_bound_) {
    coordinate_bound_ = extent;
    update_plane_bounds();
  }
}

SelectiveRefinement::Slot& SelectiveRefinement::first_use(uint32_t v) {
  if (v >= slot_count_) grow(v + 1);
  if (slots_[v].stamp != stamp_) load(v);
  return slots_[v];
}

bool SelectiveRefinement::qrefine(uint32_t slot) {
  if (!has_view_) fail(kWhere, "no view set");
  sync();
  if (slot >= mesh_->hierarchy().size()) fail(kWhere, "qrefine of an unknown slot");
  return criteria_detail::qrefine_inline(view_, state(slot).criteria);
}

// The node a split of `slot` needs split first (kim-lee-kobbelt §5.3): the deepest common ancestor of
// v̂_l and v̂_r, i.e. their longest common id prefix; kNone for a one-sided split or cuts in two trees.
// Asked only of split nodes, whose dependency is split too (SelectiveMesh keeps the partial order), so
// it is known; computed once per slot.
uint32_t SelectiveRefinement::dependency(uint32_t slot) {
  if (state(slot).dependency != kUnknown) return slots_[slot].dependency;
  const VertexHierarchy& h = mesh_->hierarchy();
  const VertexId a = h.cut_left(slot), b = h.cut_right(slot);
  uint32_t dep = kNone;
  if (is_vertex(a) && is_vertex(b) && a.tree == b.tree) {
    const int da = a.depth(), db = b.depth(), d = std::min(da, db);
    const uint64_t pa = a.node >> (da - d), pb = b.node >> (db - d);
    const uint64_t common = pa >> std::bit_width(pa ^ pb);
    // An ancestor of the slot is kept before it (the walk reaches a node through kept parents, and a
    // forced node forces its parent chain): keep() need not look at it, and that look mispredicted.
    const VertexId own = h.id(slot);
    const int below = own.depth() - (std::bit_width(common) - 1);
    if (own.tree == a.tree && below > 0 && (own.node >> below) == common) {
      slots_[slot].dependency = kNone;
      return kNone;
    }
    dep = h.find({a.tree, common});
    if (dep == kNone) return kNone;  // not known (only while the node is not split): ask again later
    state(dep);                      // decoded now, so keep() reads its slot without the checks
  }
  slots_[slot].dependency = dep;
  return dep;
}

// Keeps a split node whose slot is decoded and not kept yet this frame. `parent_kept`: v was
// reached as the child of a kept node (or is a root), so its parent needs no look. `margin`: v's plane
// bound, for its children. The stack gets v_t, v_u, then the forced parent and dependency (popped first);
// with nothing forced v_u would be popped at once, so it is returned instead, for the caller to go on.
// Then too, an active child under τ needs nothing but its evaluation counted (it is never kept and its
// visit changes nothing); v_u's visit would come at once and v_t's right after, so such a child is
// counted here instead of visited, and v_t goes without the stack when v_u needs nothing: the front's
// pairs cost no stack entry. A v_t that goes on the stack behind a v_u that needs a visit is looked at
// too, unless v was split this frame: below a node split earlier most such v_t are settled, and the
// visit's branch on them mispredicted, while a fresh pair's v_t mostly wants its split, and would pay
// the screen test twice. Not with geomorphs, which see every visit.
[[gnu::always_inline]] inline uint32_t SelectiveRefinement::keep(uint32_t v, bool parent_kept, float margin,
                                                                 bool just_split) {
  const uint32_t t = slots_[v].first_child;
  if (t + 1 >= slot_count_) grow(t + 2);
  slots_[v].kept = frame_;
  __builtin_prefetch(&slots_[t]);
  uint32_t forced[2], count = 0;
  if (!parent_kept) {
    const uint32_t parent = mesh_->hierarchy().parent(v);
    if (parent != kNone && state(parent).kept != frame_) forced[count++] = parent;
  }
  const uint32_t dep = slots_[v].dependency != kUnknown ? slots_[v].dependency : dependency(v);  // once per slot
  if (dep != kNone && slots_[dep].kept != frame_) forced[count++] = dep;
  if (count == 0) {
    if (morphs_.enabled()) {
      push_eval(t, margin);
      return t + 1;
    }
    if (settled_child(t + 1)) {
      ++counted_;
      if (!settled_child(t)) return t;
      ++counted_;
      return kNone;
    }
    if (!just_split && settled_child(t)) ++counted_;
    else push_eval(t, margin);
    return t + 1;
  }
  push_eval(t, margin);
  push_eval(t + 1, margin);
  for (uint32_t i = 0; i < count; ++i) push_forced(forced[i]);
  return kNone;
}

// An active child of a kept node that does not want a split (the screen test is the one that fails
// most): its visit would change nothing.
[[gnu::always_inline]] inline bool SelectiveRefinement::settled_child(uint32_t c) {
  return mesh_->is_active_recorded(c) && !criteria_detail::screen_error_exceeds_inline(view_, grown_state(c).criteria);
}

// A split node the target keeps (a forced entry): evaluate its children, and keep its parent and its
// dependency too.
uint32_t SelectiveRefinement::justify(uint32_t v) {
  if (mesh_->is_active(v) || state(v).kept == frame_) return kNone;
  return keep(v, false, -INFINITY, false);  // its planes were not evaluated: the children evaluate theirs
}

// qrefine of a slot the walk reached, the same answer as qrefine_inline, with the frustum test skipped
// where a bound shows it passes. On entry `margin` is a lower bound on every exact plane value at the
// parent's position; a child is at most reach from it, so margin − |n| reach bounds the child's values,
// and while that bound stays above the rounding of the child's own values no plane can cull it (a value
// ≥ 0 is never below −(radius + slack)). On return `margin` is the node's own bound, for its children.
// At a close view the planes cut few nodes: most of the walk's split nodes skip their six planes.
[[gnu::always_inline]] inline bool SelectiveRefinement::walk_qrefine(const Slot& slot, float& margin) const {
  const NodeCriteria& node = slot.criteria;
  if (!criteria_detail::screen_error_exceeds_inline(view_, node)) return false;
  margin -= slot.reach * reach_scale_ + plane_error_;
  if (!(margin >= 0)) {
    float lowest;
    if (criteria_detail::outside_frustum_inline(view_, node, lowest)) return false;
    margin = lowest - plane_error_;
  }
  return !criteria_detail::back_facing_inline(view_, node);
}

void SelectiveRefinement::report_missing(uint32_t v) {
  if (v >= reported_.size()) reported_.resize(std::max<size_t>(v + 1, 2 * reported_.size()), 0);
  if (reported_[v] == frame_) return;
  reported_[v] = frame_;
  missing_.push_back(v);
}

void SelectiveRefinement::report_forced(uint32_t v) {
  report_missing(v);
  forced_missing_.push_back(v);  // a leaf reported first as wanted may be forced too: at most once per report
}

// A vertex that wants to split but cannot yet (its own packet or one of its forced chain is missing, or
// the frame is capped): the nodes its chain already split stay, or the next frame would collapse them
// and split them again. Walks SelStreamVSplit's chain: while v_l == v_r, that vertex must split first,
// so every ancestor of it is needed.
void SelectiveRefinement::pin_chain(uint32_t v) {
  const VertexHierarchy& h = mesh_->hierarchy();
  const size_t limit = mesh_->vertex_count();
  for (size_t steps = 0; steps <= limit; ++steps) {
    if (h.is_leaf(v)) {
      if (steps == 0) report_missing(v);
      else report_forced(v);
      return;
    }
    const VertexId cut_l = h.cut_left(v), cut_r = h.cut_right(v);
    if (!is_vertex(cut_l) || !is_vertex(cut_r)) return;
    const uint32_t l = mesh_->active_ancestor(cut_l);
    if (l == kNone || l != mesh_->active_ancestor(cut_r)) return;
    if (h.parent(l) != kNone) push_forced(h.parent(l));
    v = l;
  }
}

[[gnu::always_inline]] inline uint32_t SelectiveRefinement::visit_active(uint32_t v, float& margin, FrameStats& stats) {
  const VertexHierarchy& h = mesh_->hierarchy();
  if (morphs_.enabled()) {
    morphs_.appear(h, v);
    morphs_.cancel_collapse(h, v);  // its parent is kept: a collapse under way is called off
  }
  const Slot& slot = slots_[v];  // decoded by the walk
  if (!walk_qrefine(slot, margin)) [[likely]]
    return kNone;
  if (slot.first_child == kNone) {  // a leaf of what is known
    report_missing(v);
    return kNone;
  }
  if (cap_reached(stats)) {
    stats.capped = true;
    pin_chain(v);
    return kNone;
  }
  const size_t before = mesh_->vertex_count();
  const VSplitResult r = mesh_->vsplit(v);
  stats.vsplits += uint32_t(mesh_->vertex_count() - before);
  if (r.done) return keep(v, true, margin, true);
  report_forced(r.needs);
  pin_chain(v);
  return kNone;
}

[[gnu::always_inline]] inline uint32_t SelectiveRefinement::visit_split(uint32_t v, float& margin) {
  if (walk_qrefine(slots_[v], margin)) return keep(v, true, margin, false);  // decoded, not kept: see adapt()
  tops_.push_back(v);                                                        // may still be forced later this frame
  return kNone;
}

// Kept by this frame's walk or, when the walk did not cover every tree, by any walk since every tree was
// last walked: a tree not walked this frame may still need the nodes it forced in other trees.
bool SelectiveRefinement::recently_kept(uint32_t v) const {
  const uint32_t kept = slots_[v].kept;
  return kept == frame_ || (!whole_walk_ && kept >= earlier_round_);
}

// Every split node not kept this frame lies in the subtree of a top that stayed unkept. Collapse them
// children first; a collapse the reverse partial order refuses waits for the split that depends on it
// (itself unkept, so it goes too) and is retried. After a paused walk, what other trees' last walks kept
// stays.
void SelectiveRefinement::collapse_unwanted(FrameStats& stats) {
  const VertexHierarchy& h = mesh_->hierarchy();
  collapse_.clear();
  for (uint32_t top : tops_) {
    state(top);
    if (recently_kept(top)) continue;
    const size_t first = collapse_.size();
    subtree_.clear();
    subtree_.push_back(top);
    while (!subtree_.empty()) {  // pre-order; reversed below, so children come before their parent
      const uint32_t v = subtree_.back();
      subtree_.pop_back();
      if (mesh_->is_active(v)) continue;
      if (!whole_walk_ && v != top && (state(v), recently_kept(v))) continue;  // its ancestors' collapses wait
      collapse_.push_back(v);
      subtree_.push_back(h.first_child(v));
      subtree_.push_back(h.first_child(v) + 1);
    }
    std::reverse(collapse_.begin() + ptrdiff_t(first), collapse_.end());
  }
  if (morphs_.enabled()) {
    // Children still moving toward their parent wait; the others start moving.
    size_t ready = 0;
    for (uint32_t p : collapse_) {
      const uint32_t t = h.first_child(p);
      if (!mesh_->is_active(t) || !mesh_->is_active(t + 1)) continue;
      if (morphs_.collapse_ready(h, p)) collapse_[ready++] = p;
      else morphs_.begin_collapse(h, p);
    }
    collapse_.resize(ready);
  }
  for (bool progress = true; progress && !collapse_.empty();) {
    progress = false;
    retry_.clear();
    for (uint32_t p : collapse_) {
      if (cap_reached(stats)) {
        stats.capped = true;
        return;
      }
      if (mesh_->ecol(p)) {
        ++stats.ecols;
        progress = true;
        if (morphs_.enabled()) morphs_.collapsed(h, p);
      } else {
        retry_.push_back(p);
      }
    }
    collapse_.swap(retry_);
  }
}

// Walks the forest's trees from next_root_ on; true when it walked every one. It pauses past the time
// budget only while the view moves: a view that stays is walked whole, so a frame that then finds nothing
// to do has reached the target.
bool SelectiveRefinement::walk_trees(FrameStats& stats) {
  const VertexHierarchy& h = mesh_->hierarchy();
  const uint32_t roots = h.root_count();
  const bool may_pause = options_.time_budget_us != 0 && view_moved_;
  uint32_t evaluated = 0;  // a local, not stats.evaluated: the loop's calls may write stats
  counted_ = 0;
  uint32_t walked = 0, r = next_root_ < roots ? next_root_ : 0;
  for (; walked < roots; ++walked, r = r + 1 < roots ? r + 1 : 0) {
    if (walked > 0 && may_pause && Clock::now() >= deadline_) break;
    if (r == 0) {
      earlier_round_ = round_;
      round_ = frame_;
    }
    walk_tree(r, stats, evaluated);
  }
  next_root_ = r;
  stats.evaluated = evaluated + counted_;
  if (walked < roots) return false;
  round_ = earlier_round_ = frame_;  // every tree's marks are this frame's
  return true;
}

// Top down, a root and all it leads to: a node is evaluated once its parent is kept (the root at once); a
// forced entry keeps a node whatever its qrefine, in whichever tree it is. Each node is evaluated at most
// once and kept at most once a frame.
void SelectiveRefinement::walk_tree(uint32_t root, FrameStats& stats, uint32_t& evaluated) {
  uint32_t v = mesh_->hierarchy().root_slot(root);
  if (v >= slot_count_) grow(v + 1);
  float margin = root_margin_;
  for (;;) {
    for (; v != kNone && grown_state(v).kept != frame_; ++evaluated)  // v_u of a kept node follows without the stack
      v = mesh_->is_active_recorded(v) ? visit_active(v, margin, stats) : visit_split(v, margin);
    if (stack_.empty()) return;
    const StackEntry entry = stack_.back();
    stack_.pop_back();
    v = entry.tagged >> 1;
    margin = entry.margin;
    if (entry.tagged & 1) {
      v = justify(v);
      margin = -INFINITY;
    }
  }
}

bool SelectiveRefinement::unchanged_since_settled() const {
  return settled_ && settled_changes_ == mesh_->changes() && settled_size_ == mesh_->hierarchy().size();
}

FrameStats SelectiveRefinement::adapt() {
  if (!has_view_) fail(kWhere, "no view set");
  if (unchanged_since_settled()) {
    FrameStats stats;
    stats.missing = uint32_t(missing_.size());
    return stats;
  }
  if (options_.time_budget_us) deadline_ = Clock::now() + std::chrono::microseconds(options_.time_budget_us);
  sync();
  if (++frame_ == 0) {  // stamps wrapped: clear them so old frames cannot match
    for (uint32_t v = 0; v < slot_count_; ++v)
      if (slots_[v].stamp == stamp_) slots_[v].kept = 0;
    std::fill(reported_.begin(), reported_.end(), 0);
    frame_ = 1;
    round_ = earlier_round_ = 1;
    lacked_frame_ = 0;
    next_root_ = 0;
    view_moved_ = false;  // the marks are gone: walk every tree
  }
  FrameStats stats;
  missing_.clear();
  forced_missing_.clear();
  tops_.clear();
  stack_.clear();
  whole_walk_ = walk_trees(stats);
  view_moved_ = false;
  if (!whole_walk_) stats.capped = true;
  collapse_unwanted(stats);
  if (morphs_.enabled()) stats.morphing = uint32_t(morphs_.advance(*mesh_));
  stats.missing = uint32_t(missing_.size());
  if (!missing_.empty()) lacked_frame_ = frame_;
  settled_ = stats.ops() == 0 && !stats.capped && stats.morphing == 0;
  const VertexHierarchy& h = mesh_->hierarchy();
  settled_changes_ = mesh_->changes();
  settled_size_ = uint32_t(h.size());
  return stats;
}

ConvergeStats SelectiveRefinement::converge(const Fetch& fetch, uint32_t max_frames) {
  ConvergeStats total;
  while (total.frames < max_frames) {
    const FrameStats frame = adapt();
    ++total.frames;
    total.vsplits += frame.vsplits;
    total.ecols += frame.ecols;
    size_t fetched = 0;
    if (fetch && !missing_.empty()) fetched = fetch(missing_);
    total.fetched += fetched;
    if (frame.ops() == 0 && !frame.capped && fetched == 0 && frame.morphing == 0) break;
  }
  return total;
}

void SelectiveRefinement::extract(MeshArrays& out) const {
  mesh_->extract(out);
  if (morphs_.enabled()) morphs_.apply(mesh_->hierarchy(), out);
}

size_t add_model_splits(VertexHierarchy& hierarchy, const ModelData& model, std::span<const uint32_t> leaves) {
  size_t added = 0;
  for (uint32_t slot : leaves) {
    if (slot >= hierarchy.size() || !hierarchy.is_leaf(slot)) continue;
    const uint32_t node = model.find(hierarchy.id(slot));
    if (node == kNone || model.is_leaf(node)) continue;
    hierarchy.add_split(split_record(model, node));
    ++added;
  }
  return added;
}

ViewRefineResult refine_for_view(const ModelData& model, const Camera& camera, float tolerance_px) {
  const ViewParams view = make_view(camera, model.bbox_min, model.bbox_max);
  VertexHierarchy hierarchy = VertexHierarchy::from_model(model);
  SelectiveMesh mesh(hierarchy, model.base_faces);
  AdaptOptions options;
  options.tolerance = tolerance_px;
  SelectiveRefinement refinement(mesh, model.scale, options);
  refinement.set_view(view);
  ViewRefineResult result;
  result.stats =
      refinement.converge([&](std::span<const uint32_t> leaves) { return add_model_splits(hierarchy, model, leaves); });
  refinement.extract(result.mesh);
  return result;
}

}  // namespace pms
