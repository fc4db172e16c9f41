// Geomorphs over a selectively refined mesh (Hoppe 1997 §5): vertex positions blend over N frames so
// that refinement does not pop. After vsplit(v_s) the new vertices start where v_s was shown and move to
// their own positions; before ecol(v_s) its two children move to v_s's position and the collapse is done
// only once they are there. The connectivity shown is always the mesh's own, so no frame shows a wrong
// topology, only vertices on their way. A morph interrupted by the opposite operation continues from
// where the vertex is shown.
// Shared with the browser build: single-threaded.
#pragma once
#include <cstdint>
#include <vector>

#include "spm/selective_mesh.h"
#include "spm/vertex_hierarchy.h"
#include "spm/vertex_id.h"

namespace pms {

class Geomorphs {
 public:
  explicit Geomorphs(uint32_t frames = 0) : frames_(frames) {}

  // 0 turns morphing off: every vertex shows at its own place at once and the state is forgotten.
  void set_frames(uint32_t frames);
  uint32_t frames() const { return frames_; }
  bool enabled() const { return frames_ > 0; }

  // Vertices active in `mesh` (and the split nodes above them) show at their positions: on the first
  // call the whole front, later the slots that arrived since, if active. Cost: the front once, then the
  // arrivals.
  void sync(const SelectiveMesh& mesh);

  // `v` is active and appeared by a split since it was last seen: it starts where its nearest shown
  // ancestor is shown (the split vertex, or the vertex a chain of forced splits came from). Once per
  // appearance; no-op for a vertex already shown.
  void appear(const VertexHierarchy& h, uint32_t v);
  // Both children of `p` start moving to p's position (no-op while they already are).
  void begin_collapse(const VertexHierarchy& h, uint32_t p);
  // Both children of `p` are shown at p's position: ecol(p) now changes nothing on screen.
  bool collapse_ready(const VertexHierarchy& h, uint32_t p) const;
  bool collapsing(uint32_t v) const;
  // `v` heads back to its own position from where it is shown (its collapse was called off).
  void cancel_collapse(const VertexHierarchy& h, uint32_t v);
  // ecol(p) was done: its children are gone and p shows at its position.
  void collapsed(const VertexHierarchy& h, uint32_t p);

  // One frame: each morph of an active vertex moves one step (the last step lands exactly on the
  // target); morphs of vertices that were split meanwhile stop where they are. Returns how many vertices
  // moved (children waiting at their parent for its ecol do not move).
  size_t advance(const SelectiveMesh& mesh);

  // Where active slot `v` is shown.
  const float* shown(const VertexHierarchy& h, uint32_t v) const;
  // Vertices moving or waiting at their parent for its ecol.
  size_t morphing() const { return records_.size(); }
  // Replaces out.positions (from SelectiveMesh::extract) by the shown positions.
  void apply(const VertexHierarchy& h, MeshArrays& out) const;

 private:
  struct Record {
    uint32_t slot;
    uint32_t target;  // kNone: the vertex's own position; else the parent it collapses into
    uint32_t step;
    float from[3];
  };
  const float* target_position(const VertexHierarchy& h, const Record& r) const {
    return h.position(r.target == kNone ? r.slot : r.target);
  }
  void start(uint32_t v, uint32_t target, const float* from);
  void cover(const VertexHierarchy& h, uint32_t end);  // per-slot state for slots [0, end) at least
  void show_with_ancestors(const VertexHierarchy& h, uint32_t v);
  void drop(uint32_t v);

  uint32_t frames_;
  // Per slot, up to the highest slot morphed or shown so far (grown geometrically; beyond it a slot has
  // state 0 and no record).
  std::vector<float> shown_;      // 3 per slot: valid when state_ is set
  std::vector<uint8_t> state_;    // per slot: 1 = shown_ is where it is (or was, when last active) shown
  std::vector<uint32_t> record_;  // per slot: index in records_, kNone when not morphing
  uint32_t synced_ = 0;           // hierarchy size sync() has seen; 0: not yet (or morphing was off)
  std::vector<Record> records_;
};

}  // namespace pms
