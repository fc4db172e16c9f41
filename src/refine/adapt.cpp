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
#include "refine/adapt.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>

#include "common/error.h"
#include "pm/hierarchy.h"
#include "pm/refine_info.h"
#include "pm/split_record.h"
#include "pm/vertex_id.h"
#include "refine/criteria_inline.h"
#include "refine/selective_mesh.h"
#include "refine/slot_growth.h"
#include "refine/vertex_hierarchy.h"

namespace pms {
namespace {

constexpr const char* kWhere = "selective refinement";
constexpr uint32_t kUnknown = kNone - 1;  // Slot::dependency not computed yet (slots stay below kNone - 2)

}  // namespace

SelectiveRefinement::SelectiveRefinement(SelectiveMesh& mesh, float model_scale, const AdaptOptions& options)
    : mesh_(&mesh), scale_(model_scale), synced_(mesh.hierarchy().size()) {
  static_assert(sizeof(Slot) == 64);
  set_options(options);
}

void SelectiveRefinement::set_options(const AdaptOptions& options) {
  if (!(options.tolerance >= 0) || !std::isfinite(options.tolerance)) fail(kWhere, "tolerance must be a finite number >= 0");
  if (options.morph_frames != options_.morph_frames || options.max_ops != options_.max_ops) settled_ = false;
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
  if (std::memcmp(&criteria, &view_, sizeof view_) != 0) settled_ = false;
  view_ = criteria;
}

// A split arriving for a slot already decoded: children come as a pair after their parent, and the
// first of the pair tells the parent.
void SelectiveRefinement::sync() {
  const VertexHierarchy& h = mesh_->hierarchy();
  if (morphs_.enabled()) morphs_.sync(*mesh_);
  for (uint32_t v = synced_; v < h.size(); ++v) {
    const uint32_t p = h.parent(v);
    if (p != kNone && p < slots_.size() && slots_[p].loaded && h.first_child(p) == v) slots_[p].first_child = v;
  }
  synced_ = h.size();
}

void SelectiveRefinement::grow(uint32_t end) {
  const size_t known = mesh_->hierarchy().size();
  if (end > known) fail(kWhere, "unknown slot");
  if (end <= slots_.size()) return;
  slots_.reserve(slot_capacity(end, slots_.capacity(), known, sizeof(slots_[0])));
  slots_.resize(std::min(known, std::max<size_t>(end, 2 * slots_.size())));
}

void SelectiveRefinement::load(uint32_t v) {
  const VertexHierarchy& h = mesh_->hierarchy();
  Slot& slot = slots_[v];
  slot.criteria = node_criteria(h.position(v), dequantize_refine(h.refine(v), scale_));
  slot.parent = h.parent(v);
  slot.first_child = h.first_child(v);
  slot.loaded = 1;
}

SelectiveRefinement::Slot& SelectiveRefinement::first_use(uint32_t v) {
  if (v >= slots_.size()) grow(v + 1);
  if (!slots_[v].loaded) load(v);
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
    dep = h.find({a.tree, pa >> std::bit_width(pa ^ pb)});
    if (dep == kNone) return kNone;  // not known (only while the node is not split): ask again later
  }
  slots_[slot].dependency = dep;
  return dep;
}

// A split node the target keeps: evaluate its children, and keep its parent and its dependency too.
void SelectiveRefinement::justify(uint32_t v) {
  if (!mesh_->is_active(v) && state(v).kept != frame_) keep(v, false);
}

// justify() of a split node whose slot is decoded and not kept yet this frame. `parent_kept`: v was
// reached as the child of a kept node (or is a root), so its parent needs no look.
void SelectiveRefinement::keep(uint32_t v, bool parent_kept) {
  const uint32_t t = slots_[v].first_child;
  if (t + 1 >= slots_.size()) grow(t + 2);  // before taking references: it may move the slots
  Slot& slot = slots_[v];
  slot.kept = frame_;
  __builtin_prefetch(&slots_[t]);
  __builtin_prefetch(&slots_[t + 1]);
  push_eval(t);
  push_eval(t + 1);
  if (!parent_kept && slot.parent != kNone && state(slot.parent).kept != frame_) push_forced(slot.parent);
  const uint32_t dep = slot.dependency != kUnknown ? slot.dependency : dependency(v);  // computed once per slot
  if (dep != kNone && state(dep).kept != frame_) push_forced(dep);
}

void SelectiveRefinement::report_missing(uint32_t v) {
  if (v >= reported_.size()) reported_.resize(std::max<size_t>(v + 1, 2 * reported_.size()), 0);
  if (reported_[v] == frame_) return;
  reported_[v] = frame_;
  missing_.push_back(v);
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
      report_missing(v);
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

void SelectiveRefinement::visit_active(uint32_t v, FrameStats& stats) {
  const VertexHierarchy& h = mesh_->hierarchy();
  if (morphs_.enabled()) {
    morphs_.appear(h, v);
    morphs_.cancel_collapse(h, v);  // its parent is kept: a collapse under way is called off
  }
  ++stats.evaluated;
  const Slot& slot = slots_[v];  // decoded by the walk
  if (!criteria_detail::qrefine_inline(view_, slot.criteria)) return;
  if (slot.first_child == kNone) {  // a leaf of what is known
    report_missing(v);
    return;
  }
  if (cap_reached(stats)) {
    stats.capped = true;
    pin_chain(v);
    return;
  }
  const size_t before = mesh_->vertex_count();
  const VSplitResult r = mesh_->vsplit(v);
  stats.vsplits += uint32_t(mesh_->vertex_count() - before);
  if (r.done) {
    keep(v, true);
  } else {
    report_missing(r.needs);
    pin_chain(v);
  }
}

void SelectiveRefinement::visit_split(uint32_t v, FrameStats& stats) {
  ++stats.evaluated;
  if (criteria_detail::qrefine_inline(view_, slots_[v].criteria)) keep(v, true);  // decoded, not kept: see adapt()
  else tops_.push_back(v);  // may still be forced later this frame
}

// Every split node not kept this frame lies in the subtree of a top that stayed unkept. Collapse them
// children first; a collapse the reverse partial order refuses waits for the split that depends on it
// (itself unkept, so it goes too) and is retried.
void SelectiveRefinement::collapse_unwanted(FrameStats& stats) {
  const VertexHierarchy& h = mesh_->hierarchy();
  collapse_.clear();
  for (uint32_t top : tops_) {
    if (state(top).kept == frame_) continue;
    const size_t first = collapse_.size();
    stack_.clear();
    stack_.push_back(top);
    while (!stack_.empty()) {  // pre-order; reversed below, so children come before their parent
      const uint32_t v = uint32_t(stack_.back());
      stack_.pop_back();
      if (mesh_->is_active(v)) continue;
      collapse_.push_back(v);
      stack_.push_back(h.first_child(v));
      stack_.push_back(h.first_child(v) + 1);
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
  sync();
  if (++frame_ == 0) {  // stamps wrapped: clear them so old frames cannot match
    for (Slot& slot : slots_) slot.kept = 0;
    std::fill(reported_.begin(), reported_.end(), 0);
    frame_ = 1;
  }
  FrameStats stats;
  missing_.clear();
  tops_.clear();
  stack_.clear();
  const VertexHierarchy& h = mesh_->hierarchy();
  for (uint32_t r = h.root_count(); r-- > 0;) push_eval(h.root_slot(r));
  // Top down: a node is evaluated once its parent is kept (roots at once); a forced entry keeps a node
  // whatever its qrefine. Each node is evaluated at most once and kept at most once.
  while (!stack_.empty()) {
    const uint64_t entry = stack_.back();
    stack_.pop_back();
    const uint32_t v = uint32_t(entry >> 1);
    if (entry & 1) {
      justify(v);
    } else if (state(v).kept != frame_) {
      if (mesh_->is_active(v)) visit_active(v, stats);
      else visit_split(v, stats);
    }
  }
  collapse_unwanted(stats);
  if (morphs_.enabled()) stats.morphing = uint32_t(morphs_.advance(*mesh_));
  stats.missing = uint32_t(missing_.size());
  settled_ = stats.ops() == 0 && !stats.capped && stats.morphing == 0;
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
    if (frame.ops() == 0 && fetched == 0 && frame.morphing == 0) break;
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
  result.stats = refinement.converge(
      [&](std::span<const uint32_t> leaves) { return add_model_splits(hierarchy, model, leaves); });
  refinement.extract(result.mesh);
  return result;
}

}  // namespace pms
