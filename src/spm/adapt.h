// View-dependent adaptation of a SelectiveMesh, frame by frame (Hoppe 1997 §5; the client loop
// SelectiveRefinement of kim-lee-kobbelt 2005 §5.3): split where qrefine() asks, collapse where it no
// longer does, report the known leaves whose vsplit packets are needed, optionally with geomorphs.
// docs/internals.md ("Adaptation loop") explains the target mesh and why the loop reaches it.
// Shared with the browser build: single-threaded, no std::ranges algorithms, std::format or coroutines.
#pragma once
#include <chrono>
#include <cmath>
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "common/camera.h"
#include "common/huge_pages.h"
#include "spm/criteria.h"
#include "spm/geomorph.h"
#include "spm/hierarchy.h"
#include "spm/selective_mesh.h"
#include "spm/slot_array.h"
#include "spm/vertex_hierarchy.h"
#include "spm/vertex_id.h"

namespace pms {

struct AdaptOptions {
  float tolerance = 1;        // τ: screen-space error in pixels
  uint32_t max_ops = 0;       // vsplits + ecols per frame (a forced chain counts each split); 0 = no cap
  uint32_t morph_frames = 0;  // geomorph length in frames; 0 = off (viewers use kDefaultMorphFrames)
  // Wall time a frame's walk and operations may take, in microseconds; 0 = no limit. Past it the frame
  // stops as at max_ops (capped) once it has done kMinOpsPerBudgetedFrame operations, so a frame whose walk
  // alone overruns still makes progress. While the view moves, the walk itself also pauses at the next
  // tree of the forest past it, and the next frame goes on from there (Hoppe 1997 amortizes the traversal
  // over frames the same way); a view that stays is walked whole, so the frames still settle on its target.
  // A viewer sets it to keep its frames short whatever the front's size: a burst of collapses (a region
  // leaving the view) then spreads over frames instead of stalling one.
  uint32_t time_budget_us = 0;
};
constexpr uint32_t kMinOpsPerBudgetedFrame = 8;
constexpr uint32_t kDefaultMorphFrames = 8;

struct FrameStats {
  uint32_t vsplits = 0;  // splits done, including those the partial order forced
  uint32_t ecols = 0;
  uint32_t missing = 0;    // leaves reported by missing()
  uint32_t evaluated = 0;  // qrefine evaluations
  uint32_t morphing = 0;   // vertices that moved this frame (geomorphs)
  // Stopped at max_ops or time_budget_us, its operations or its walk (some trees were not walked): more
  // work is left for the next frames.
  bool capped = false;
  uint32_t ops() const { return vsplits + ecols; }
};

struct ConvergeStats {
  uint32_t frames = 0;
  uint64_t vsplits = 0, ecols = 0;
  uint64_t fetched = 0;  // splits the fetch callback added
};

// Owns no mesh: adapts `mesh` (and reads its hierarchy, which may grow between frames as packets arrive).
// `model_scale` is the model's scale (ModelData::scale): refinement info is decoded with it.
class SelectiveRefinement {
 public:
  SelectiveRefinement(SelectiveMesh& mesh, float model_scale, const AdaptOptions& options = {});

  void set_options(const AdaptOptions& options);
  const AdaptOptions& options() const { return options_; }
  // The view for the next frames, with options().tolerance; pms::Error for a negative tolerance.
  void set_view(const ViewParams& view);

  // One frame. After a frame that changed nothing (no operation, cap or movement), with the same criteria
  // (view and τ), options, hierarchy and mesh, the walk would reach the same result: it returns at once
  // (evaluated 0, the same missing()). Otherwise it walks the split forest from the roots and evaluates
  // qrefine once per node it reaches:
  // splits active vertices that want it (the partial order's forced chain included), keeps a split node
  // while it is wanted, forced by a kept split, or an ancestor of one, and collapses the rest (after a
  // geomorph when morph_frames > 0). Known leaves that want a split whose packet is unknown go to missing().
  FrameStats adapt();
  // The last adapt() changed nothing and left nothing to do (no operation, no cap reached, nothing
  // moving), or there was none yet: another one at the same view and hierarchy would change nothing. False
  // after a frame that operated: its collapses may have left a parent that only the next walk finds
  // unwanted, and a capped frame left work.
  bool at_rest() const { return settled_ || frame_ == 0; }
  // The next adapt() walks even when nothing changed (benchmarks time the walk with it).
  void rewalk() { settled_ = false; }

  // Active known leaves (slots) that qrefine wants split but whose vsplit packet is not known, including
  // the leaf a forced chain stopped at, among the trees the last adapt() walked. Valid until the next
  // adapt(): the streaming client asks for them.
  std::span<const uint32_t> missing() const { return missing_; }
  // Of missing(), the leaves forced chains stopped at: splits some wanted split depends on (the partial
  // order), which a client that chooses its splits by another rule than qrefine must still fetch. A leaf
  // may be listed more than once.
  std::span<const uint32_t> forced_missing() const { return forced_missing_; }
  // Some leaf wants a packet the hierarchy lacks: missing() is not empty, or, after a walk the time budget
  // paused, a frame since every tree was last walked reported one.
  bool lacks_packets() const { return !missing_.empty() || (lacked_frame_ != 0 && lacked_frame_ >= earlier_round_); }

  // Adds the vsplit packets of (some of) `leaves` to the hierarchy; returns how many it added.
  using Fetch = std::function<size_t(std::span<const uint32_t> leaves)>;
  // adapt() until a frame changes nothing, moves nothing and `fetch` (if given) adds nothing more.
  // With every packet available the result is the target mesh of the view, whatever the mesh was.
  ConvergeStats converge(const Fetch& fetch = {}, uint32_t max_frames = 1u << 20);

  // The mesh with vertices at their shown (morphed) positions.
  void extract(MeshArrays& out) const;
  const Geomorphs& geomorphs() const { return morphs_; }
  const SelectiveMesh& mesh() const { return *mesh_; }
  // qrefine(v) for a known slot under the current view.
  bool qrefine(uint32_t slot);

 private:
  void sync();
  bool unchanged_since_settled() const;
  void use_criteria(const ViewCriteria& criteria);
  void update_plane_bounds();
  struct Slot;
  // v's slot, grown and decoded on first use (out of line: the walk's fast path stays small).
  Slot& state(uint32_t v) {
    if (v < slot_count_ && slots_[v].stamp == stamp_) [[likely]]
      return slots_[v];
    return first_use(v);
  }
  Slot& first_use(uint32_t v);
  // state() of a slot below slot_count_ (the walk grows the slots before it reaches them).
  Slot& grown_state(uint32_t v) {
    if (slots_[v].stamp == stamp_) [[likely]]
      return slots_[v];
    return first_use(v);
  }
  void grow(uint32_t end);
  void load(uint32_t v);
  uint32_t dependency(uint32_t slot);
  // A node to evaluate, with its parent's plane bound (`margin`, see walk_qrefine), or one to keep.
  struct StackEntry {
    uint32_t tagged;  // slot << 1 | forced
    float margin;
  };
  void push_eval(uint32_t v, float margin) { stack_.push_back({v << 1, margin}); }
  void push_forced(uint32_t v) { stack_.push_back({v << 1 | 1, 0}); }
  // The walk's steps return the node to evaluate next when it is the one the stack would give next
  // (kNone otherwise), so the common case skips a push and a pop.
  uint32_t justify(uint32_t v);
  uint32_t keep(uint32_t v, bool parent_kept, float margin, bool just_split);
  bool settled_child(uint32_t c);
  bool walk_qrefine(const Slot& slot, float& margin) const;
  uint32_t visit_active(uint32_t v, float& margin, FrameStats& stats);
  uint32_t visit_split(uint32_t v, float& margin);
  void pin_chain(uint32_t v);
  void report_missing(uint32_t v);
  void report_forced(uint32_t v);
  bool walk_trees(FrameStats& stats);
  void walk_tree(uint32_t root, FrameStats& stats, uint32_t& evaluated);
  bool recently_kept(uint32_t v) const;
  void collapse_unwanted(FrameStats& stats);
  bool cap_reached(const FrameStats& stats) const {
    if (options_.max_ops && stats.ops() >= options_.max_ops) return true;
    return options_.time_budget_us && stats.ops() >= kMinOpsPerBudgetedFrame && Clock::now() >= deadline_;
  }

  SelectiveMesh* mesh_;
  float scale_;  // the model's, as the decoder applies it (dequantize_detail::effective_scale)
  AdaptOptions options_;
  ViewParams view_params_;
  ViewCriteria view_;
  bool has_view_ = false;
  uint32_t frame_ = 0;
  uint32_t counted_ = 0;  // evaluations keep() counted for the visits it saved (this frame)
  // The last frame changed nothing (no operation, cap or movement); valid while view, options,
  // hierarchy size and mesh changes() stay as they were then.
  bool settled_ = false;
  // The criteria changed since the last adapt(): the time budget may pause the walk (AdaptOptions).
  bool view_moved_ = false;
  // A paused walk goes on at next_root_ in the next frame. A node another tree's walk kept (forced) is
  // kept until every tree has been walked again: `round_` is the frame in which the walk last began at
  // root 0 (or walked every tree), `earlier_round_` the one before, and every tree's last walk is at or
  // after `earlier_round_`. This frame's walk covered every tree: `whole_walk_`.
  uint32_t next_root_ = 0;
  uint32_t round_ = 1, earlier_round_ = 1;
  bool whole_walk_ = true;
  uint32_t lacked_frame_ = 0;  // the last frame whose missing() was not empty
  using Clock = std::chrono::steady_clock;
  Clock::time_point deadline_;  // this frame's, with options().time_budget_us
  uint64_t settled_changes_ = 0;
  uint32_t settled_size_ = 0;
  // Everything the walk reads of a slot, in one cache line: the walk is bound by memory latency. Slots
  // are never initialised as a whole (spm/slot_array.h) and are decoded when first reached, so a
  // fresh refinement pays for the nodes it evaluates, not for the model.
  struct alignas(64) Slot {
    NodeCriteria criteria;  // decoded once
    uint32_t kept = 0;      // frame in which the node was found wanted or forced
    uint32_t first_child = kNone;
    uint32_t dependency = kNone - 1;  // the node its split needs split (partial order); kNone - 1: not computed
    float reach = 0;                  // |p − p_parent| (a root: |p − root_centre_|), rounded up
    uint32_t stamp = 0;               // stamp_ once load() has set every field (else stale or zero bytes)
  };
  static constexpr int kSlotArrayKind = 2;  // SlotArray's kind: blocks go back to the next refinement's slots
  SlotArray<Slot, kSlotArrayKind> slots_;   // on huge pages: the walk reads them at random
  uint32_t slot_count_ = 0;                 // slots_.size(), one compare for the walk
  // This refinement's mark on the slots it loaded, unique in the process: a slot array's blocks pass
  // from one refinement to the next with the old slots in them.
  uint32_t stamp_;
  uint32_t synced_ = 0;             // hierarchy size whose new children pairs the loaded slots know of
  std::vector<uint32_t> reported_;  // per slot: frame in which it went to missing_ (grown on use)
  // The plane bounds of walk_qrefine: every loaded position's coordinates are within ±coordinate_bound_,
  // so a plane value computed in float is within plane_error_ of the exact one; reach_scale_ is at least
  // every plane's |n|, so reach · reach_scale_ bounds how far a plane value moves from parent to child.
  // The roots are bounded from root_centre_, whose bound is root_margin_.
  float coordinate_bound_ = 0, plane_error_ = 0, reach_scale_ = 1;
  float root_centre_[3] = {0, 0, 0}, root_margin_ = -INFINITY;
  std::vector<StackEntry> stack_;
  std::vector<uint32_t> tops_;  // split nodes not wanted, whose subtrees may have to collapse
  std::vector<uint32_t> subtree_, collapse_, retry_;
  std::vector<uint32_t> missing_;
  std::vector<uint32_t> forced_missing_;  // of missing_, once per report (a leaf may be forced twice)
  Geomorphs morphs_;
};

// Local refinement of a complete model: adds the vsplit packets of those `leaves` that are internal nodes
// of `model` (a Fetch for SelectiveRefinement::converge). Returns how many it added.
size_t add_model_splits(VertexHierarchy& hierarchy, const ModelData& model, std::span<const uint32_t> leaves);

struct ViewRefineResult {
  MeshArrays mesh;
  ConvergeStats stats;
};

// The mesh of `model` for one view: from the base mesh, splits fetched from the model as the loop asks
// for them, run to convergence (no geomorphs).
ViewRefineResult refine_for_view(const ModelData& model, const Camera& camera, float tolerance_px);

}  // namespace pms
