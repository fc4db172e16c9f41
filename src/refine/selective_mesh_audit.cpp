// Reading a SelectiveMesh out: flat arrays for renderers and exporters, and the connectivity audit the
// property tests run after every operation (DESIGN.md §6 property 2).
#include <algorithm>

#include "common/error.h"
#include "refine/refine.h"

namespace pms {

void SelectiveMesh::extract(MeshArrays& out) const {
  const VertexHierarchy& h = *hierarchy_;
  out.slots.assign(active_.begin(), active_.end());
  out.positions.resize(3 * active_.size());
  out.normals.resize(h.has_normals() ? 3 * active_.size() : 0);
  out.colors.resize(h.has_colors() ? 4 * active_.size() : 0);
  for (size_t i = 0; i < active_.size(); ++i) {
    std::copy_n(h.position(active_[i]), 3, &out.positions[3 * i]);
    if (h.has_normals()) std::copy_n(h.normal(active_[i]), 3, &out.normals[3 * i]);
    if (h.has_colors()) std::copy_n(h.color(active_[i]), 4, &out.colors[4 * i]);
  }
  // active_pos_ is exactly the output numbering.
  out.indices.clear();
  out.indices.reserve(3 * face_count_);
  for (uint32_t f = 0; f < face_capacity(); ++f) {
    if (!face_alive(f)) continue;
    for (int k = 0; k < 3; ++k) out.indices.push_back(active_pos_[corner_[3 * size_t(f) + k]]);
  }
}

namespace {

bool fail_with(std::string* why, const std::string& what) {
  if (why) *why = what;
  return false;
}

}  // namespace

bool SelectiveMesh::check_invariants(std::string* why) const {
  const VertexHierarchy& h = *hierarchy_;
  const uint32_t slots = uint32_t(out_.size());
  if (slots > h.size()) return fail_with(why, "more vertex slots than hierarchy nodes");
  const auto name = [&](uint32_t v) { return to_string(h.id(v)); };

  // Faces: three distinct active corners; the free list holds exactly the dead ones.
  size_t alive = 0, dead = 0;
  for (uint32_t f = 0; f < face_capacity(); ++f) {
    if (!face_alive(f)) continue;
    ++alive;
    const uint32_t* c = face(f);
    for (int k = 0; k < 3; ++k)
      if (!is_active(c[k])) return fail_with(why, "face " + std::to_string(f) + " uses an inactive vertex");
    if (c[0] == c[1] || c[1] == c[2] || c[2] == c[0]) return fail_with(why, "face " + std::to_string(f) + " is degenerate");
  }
  for (uint32_t f = free_face_; f != kNone; f = corner_[3 * size_t(f) + 1]) {
    if (f >= face_capacity() || face_alive(f) || ++dead > face_capacity()) return fail_with(why, "corrupted free list");
  }
  if (alive != face_count_ || alive + dead != face_capacity()) return fail_with(why, "face count does not match");

  // Half-edges: twins symmetric and reversed; each directed edge once; a boundary half-edge has no
  // reverse anywhere (otherwise a twin link is missing).
  std::vector<uint64_t> edges;
  edges.reserve(3 * alive);
  for (uint32_t e = 0; e < corner_.size(); ++e) {
    if (!face_alive(e / 3)) continue;
    edges.push_back(uint64_t(corner_[e]) << 32 | head(e));
    const uint32_t tw = twin_[e];
    if (tw == kNone) continue;
    if (tw >= twin_.size() || !face_alive(tw / 3) || twin_[tw] != e || corner_[tw] != head(e) || head(tw) != corner_[e])
      return fail_with(why, "half-edge " + std::to_string(e) + " has an inconsistent twin");
  }
  std::sort(edges.begin(), edges.end());
  if (std::adjacent_find(edges.begin(), edges.end()) != edges.end())
    return fail_with(why, "a directed edge occurs twice");
  for (uint32_t e = 0; e < corner_.size(); ++e) {
    if (!face_alive(e / 3) || twin_[e] != kNone) continue;
    if (std::binary_search(edges.begin(), edges.end(), uint64_t(head(e)) << 32 | corner_[e]))
      return fail_with(why, "boundary half-edge " + std::to_string(e) + " has an unlinked reverse");
  }

  // Vertices: an active vertex has faces forming one fan reachable from its half-edge; the active set
  // is a front (no active vertex has an active ancestor) listed once in active_.
  std::vector<uint32_t> corners(slots, 0);
  for (uint32_t e = 0; e < corner_.size(); ++e)
    if (face_alive(e / 3)) ++corners[corner_[e]];
  size_t active_count = 0;
  std::vector<uint32_t> fan;
  for (uint32_t v = 0; v < slots; ++v) {
    if (!is_active(v)) {
      if (corners[v] != 0) return fail_with(why, "inactive vertex " + name(v) + " has faces");
      continue;
    }
    ++active_count;
    const uint32_t o = out_[v];
    if (o >= corner_.size() || !face_alive(o / 3) || corner_[o] != v)
      return fail_with(why, "vertex " + name(v) + " has an invalid outgoing half-edge");
    try {
      gather_fan(v, fan);
    } catch (const Error& e) {
      return fail_with(why, e.what());
    }
    if (fan.size() != corners[v]) return fail_with(why, "vertex " + name(v) + " is non-manifold (several fans)");
    if (active_pos_[v] >= active_.size() || active_[active_pos_[v]] != v)
      return fail_with(why, "vertex " + name(v) + " is missing from the active list");
    for (uint32_t a = h.parent(v); a != kNone; a = h.parent(a))
      if (is_active(a)) return fail_with(why, "vertex " + name(v) + " and its ancestor " + name(a) + " are both active");
  }
  if (active_count != active_.size()) return fail_with(why, "active list has stale entries");

  // The partial order (kim-lee-kobbelt §5.3): every performed split (a known node above the front)
  // still has distinct active ancestors for its two cut vertices.
  for (uint32_t q = 0; q < slots; ++q) {
    if (h.is_leaf(q) || is_active(q) || active_ancestor(h.id(q)) != kNone) continue;
    const VertexId cut_l = h.cut_left(q), cut_r = h.cut_right(q);
    if (is_vertex(cut_l) && is_vertex(cut_r) && active_ancestor(cut_l) == active_ancestor(cut_r))
      return fail_with(why, "split " + name(q) + " has both cut vertices below " + name(active_ancestor(cut_l)));
  }
  return true;
}

}  // namespace pms
