// Geomorphs (Hoppe 1997 §5, "vsplit and ecol geomorphs"): linear blends of vertex positions over a
// fixed number of frames, one record per moving vertex, in a flat array with per-slot indices.
#include "spm/geomorph.h"

#include <algorithm>

#include "spm/selective_mesh.h"
#include "spm/vertex_hierarchy.h"
#include "spm/vertex_id.h"

namespace pms {

void Geomorphs::set_frames(uint32_t frames) {
  frames_ = frames;
  if (frames_ > 0) return;
  // Off: every vertex shows at its own place and collapses no longer wait; sync() starts afresh.
  shown_.clear();
  state_.clear();
  record_.clear();
  records_.clear();
  synced_ = 0;
}

void Geomorphs::cover(const VertexHierarchy& h, uint32_t end) {
  if (end <= state_.size()) return;
  const size_t n = std::min<size_t>(h.size(), std::max<size_t>(end, 2 * state_.size()));
  shown_.resize(3 * n);
  state_.resize(n, 0);
  record_.resize(n, kNone);
}

// A parent's slot is below its children's (they arrive after it), so covering v covers its ancestors.
void Geomorphs::show_with_ancestors(const VertexHierarchy& h, uint32_t v) {
  cover(h, v + 1);
  for (uint32_t a = v; a != kNone && !state_[a]; a = h.parent(a)) {
    state_[a] = 1;
    std::copy_n(h.position(a), 3, &shown_[3 * size_t(a)]);
  }
}

// Shown: active, or above the front (a mesh handed over already refined); a node below the front gets
// its place when it appears. Split nodes are exactly the ancestors of active ones.
void Geomorphs::sync(const SelectiveMesh& mesh) {
  const VertexHierarchy& h = mesh.hierarchy();
  if (synced_ == 0) {
    for (uint32_t v : mesh.active_vertices()) show_with_ancestors(h, v);
  } else {
    for (uint32_t v = synced_; v < h.size(); ++v)
      if (mesh.is_active(v)) show_with_ancestors(h, v);
  }
  synced_ = h.size();
}

void Geomorphs::start(uint32_t v, uint32_t target, const float* from) {
  if (record_[v] == kNone) {  // covered by the caller
    record_[v] = uint32_t(records_.size());
    records_.push_back({});
  }
  Record& r = records_[record_[v]];
  r.slot = v;
  r.target = target;
  r.step = 0;
  std::copy_n(from, 3, r.from);
}

void Geomorphs::drop(uint32_t v) {
  if (v >= record_.size()) return;
  const uint32_t i = record_[v];
  if (i == kNone) return;
  records_[i] = records_.back();
  record_[records_[i].slot] = i;
  records_.pop_back();
  record_[v] = kNone;
}

void Geomorphs::appear(const VertexHierarchy& h, uint32_t v) {
  cover(h, v + 1);
  if (state_[v]) return;
  // The nearest ancestor shown on screen: the parent, unless the parent itself was split before it was
  // ever shown (a forced chain); roots are always shown.
  uint32_t a = h.parent(v);
  while (a != kNone && !state_[a]) a = h.parent(a);
  const float* from = a != kNone ? &shown_[3 * size_t(a)] : h.position(v);
  float* shown = &shown_[3 * size_t(v)];
  std::copy_n(from, 3, shown);
  state_[v] = 1;
  drop(v);
  if (!std::equal(from, from + 3, h.position(v))) start(v, kNone, shown);  // v_u of a still parent: nothing to do
}

void Geomorphs::begin_collapse(const VertexHierarchy& h, uint32_t p) {
  const uint32_t t = h.first_child(p);
  cover(h, t + 2);
  for (uint32_t c : {t, t + 1}) {
    if (record_[c] != kNone && records_[record_[c]].target == p) continue;  // already under way
    start(c, p, &shown_[3 * size_t(c)]);
  }
}

bool Geomorphs::collapse_ready(const VertexHierarchy& h, uint32_t p) const {
  const uint32_t t = h.first_child(p);
  for (uint32_t c : {t, t + 1}) {
    const uint32_t i = c < record_.size() ? record_[c] : kNone;
    if (i == kNone || records_[i].target != p || records_[i].step < frames_) return false;
  }
  return true;
}

bool Geomorphs::collapsing(uint32_t v) const {
  return v < record_.size() && record_[v] != kNone && records_[record_[v]].target != kNone;
}

void Geomorphs::cancel_collapse(const VertexHierarchy& h, uint32_t v) {
  if (!collapsing(v)) return;
  const float* shown = &shown_[3 * size_t(v)];
  if (std::equal(shown, shown + 3, h.position(v))) drop(v);
  else start(v, kNone, shown);
}

void Geomorphs::collapsed(const VertexHierarchy& h, uint32_t p) {
  const uint32_t t = h.first_child(p);
  cover(h, t + 2);
  for (uint32_t c : {t, t + 1}) {
    drop(c);
    state_[c] = 0;
  }
  drop(p);
  state_[p] = 1;
  std::copy_n(h.position(p), 3, &shown_[3 * size_t(p)]);
}

size_t Geomorphs::advance(const SelectiveMesh& mesh) {
  const VertexHierarchy& h = mesh.hierarchy();
  size_t moved = 0;
  for (size_t i = 0; i < records_.size();) {
    Record& r = records_[i];
    if (!mesh.is_active(r.slot)) {  // split meanwhile: its shown place is where its children came from
      drop(r.slot);
      continue;
    }
    float* shown = &shown_[3 * size_t(r.slot)];
    const float* to = target_position(h, r);
    if (r.step < frames_) {
      ++r.step;
      ++moved;
    }
    if (r.step >= frames_) {
      std::copy_n(to, 3, shown);  // exactly the target, not a rounded blend
      if (r.target == kNone) {
        drop(r.slot);
        continue;
      }
    } else {
      const float w = float(r.step) / float(frames_);
      for (int k = 0; k < 3; ++k) shown[k] = r.from[k] + (to[k] - r.from[k]) * w;
    }
    ++i;
  }
  return moved;
}

const float* Geomorphs::shown(const VertexHierarchy& h, uint32_t v) const {
  return v < state_.size() && state_[v] ? &shown_[3 * size_t(v)] : h.position(v);
}

void Geomorphs::apply(const VertexHierarchy& h, MeshArrays& out) const {
  if (records_.empty()) return;  // every active vertex is where it belongs
  for (size_t i = 0; i < out.slots.size(); ++i) std::copy_n(shown(h, out.slots[i]), 3, &out.positions[3 * i]);
}

}  // namespace pms
