// Reading a SelectiveMesh out: flat arrays for renderers and exporters, and the connectivity audit the
// property tests run after every operation (property 2 of docs/architecture.md, "Correctness properties").
#include <algorithm>
#include <bit>

#include "common/error.h"
#include "spm/selective_mesh.h"
#include "spm/vertex_hierarchy.h"
#include "spm/vertex_id.h"

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
  // active_pos is exactly the output numbering.
  out.indices.clear();
  out.indices.reserve(3 * face_count_);
  for (uint32_t f = 0; f < face_capacity(); ++f) {
    if (!face_alive(f)) continue;
    for (int k = 0; k < 3; ++k) out.indices.push_back(vertex_[corner_[3 * size_t(f) + k]].active_pos);
  }
}

namespace {

bool fail_with(std::string* why, const std::string& what) {
  if (why) *why = what;
  return false;
}

}  // namespace

// `list` is `ordered` (a fan's faces in fan order) shifted round when the fan is closed, as it is when it
// is open: an open fan's list starts after its gap.
bool SelectiveMesh::in_fan_order(const uint32_t* list, const std::vector<Corner>& ordered, bool closed) {
  const size_t n = ordered.size();
  if (n == 0) return true;
  const size_t shift = size_t(std::find(list, list + n, ordered[0].face) - list);
  if (shift == n || (!closed && shift != 0)) return false;
  for (size_t i = 0; i < n; ++i)
    if (list[(shift + i) % n] != ordered[i].face) return false;
  return true;
}

// The blocks in use (`blocks`) and the free ones, walked per size class, tile part of the pool without
// overlapping: a list written past its block would corrupt its neighbour's.
bool SelectiveMesh::pool_blocks_disjoint(std::vector<std::pair<uint32_t, uint32_t>>& blocks) const {
  for (int size_class = 0; size_class < 32; ++size_class) {
    const uint32_t capacity = 1u << size_class;
    size_t walked = 0;
    for (uint32_t b = free_block_[size_class]; b != kNone; b = pool_[b]) {
      if (b >= pool_.size() || ++walked > pool_.size() / capacity) return false;
      blocks.push_back({b, capacity});
    }
  }
  std::sort(blocks.begin(), blocks.end());
  for (size_t i = 0; i < blocks.size(); ++i) {
    const uint64_t end = uint64_t(blocks[i].first) + blocks[i].second;
    if (end > pool_.size() || (i + 1 < blocks.size() && end > blocks[i + 1].first)) return false;
  }
  return true;
}

bool SelectiveMesh::check_invariants(std::string* why) const {
  const VertexHierarchy& h = *hierarchy_;
  const uint32_t slots = uint32_t(std::min<size_t>(vertex_.size(), h.size()));  // records may run past it
  const auto name = [&](uint32_t v) { return to_string(h.id(v)); };

  // Faces: three distinct active corners; the free list holds exactly the dead ones.
  size_t alive = 0, dead = 0;
  for (uint32_t f = 0; f < face_capacity(); ++f) {
    if (!face_alive(f)) continue;
    ++alive;
    const uint32_t* c = face(f);
    for (int k = 0; k < 3; ++k)
      if (!is_active(c[k])) return fail_with(why, "face " + std::to_string(f) + " uses an inactive vertex");
    if (c[0] == c[1] || c[1] == c[2] || c[2] == c[0])
      return fail_with(why, "face " + std::to_string(f) + " is degenerate");
  }
  for (uint32_t f = free_face_; f != kNone; f = corner_[3 * size_t(f) + 1]) {
    if (f >= face_capacity() || face_alive(f) || ++dead > face_capacity()) return fail_with(why, "corrupted free list");
  }
  if (alive != face_count_ || alive + dead != face_capacity()) return fail_with(why, "face count does not match");

  // Each directed edge once; the faces of one split name each other.
  std::vector<uint64_t> edges;
  edges.reserve(3 * alive);
  for (uint32_t f = 0; f < face_capacity(); ++f) {
    if (!face_alive(f)) continue;
    const uint32_t* c = face(f);
    for (int k = 0; k < 3; ++k) edges.push_back(uint64_t(c[k]) << 32 | c[(k + 1) % 3]);
    const uint32_t other = partner_[f];
    if (other != kNone && (other >= face_capacity() || !face_alive(other) || partner_[other] != f))
      return fail_with(why, "face " + std::to_string(f) + " has an inconsistent partner");
  }
  std::sort(edges.begin(), edges.end());
  if (std::adjacent_find(edges.begin(), edges.end()) != edges.end())
    return fail_with(why, "a directed edge occurs twice");

  // Vertices: an active vertex lists exactly the faces it is a corner of, once each, and they form one
  // fan; the active set is a front (no active vertex has an active ancestor) listed once in active_.
  std::vector<uint32_t> corners(vertex_.size(), 0);
  for (uint32_t c = 0; c < corner_.size(); ++c)
    if (face_alive(c / 3)) {
      if (corner_[c] >= slots)
        return fail_with(why, "face " + std::to_string(c / 3) + " has a corner past the hierarchy");
      ++corners[corner_[c]];
    }
  for (uint32_t v = slots; v < vertex_.size(); ++v)
    if (is_active(v)) return fail_with(why, "an active vertex past the hierarchy");
  size_t active_count = 0;
  std::vector<uint32_t> listed, successor;
  std::vector<std::pair<uint32_t, uint32_t>> blocks;  // pool blocks in use: (begin, capacity)
  std::vector<Corner> fan, ordered;
  for (uint32_t v = 0; v < slots; ++v) {
    if (!is_active(v)) {
      if (corners[v] != 0) return fail_with(why, "inactive vertex " + name(v) + " has faces");
      continue;
    }
    ++active_count;
    const VertexRecord& record = vertex_[v];
    if (id_of(v) != h.id(v)) return fail_with(why, "vertex " + name(v) + " has a stale id copy");
    if (record.size > record.capacity || (record.capacity != kInlineFaces && !std::has_single_bit(record.capacity)))
      return fail_with(why, "vertex " + name(v) + " has an invalid face list");
    if (record.capacity > kInlineFaces) blocks.push_back({record.inline_faces[0], record.capacity});
    listed.assign(faces_of(record), faces_of(record) + record.size);
    std::sort(listed.begin(), listed.end());
    if (std::adjacent_find(listed.begin(), listed.end()) != listed.end() || listed.size() != corners[v])
      return fail_with(why, "vertex " + name(v) + " lists a face twice or misses one");
    for (uint32_t f : listed) {
      if (f >= face_capacity() || !face_alive(f) || std::count(face(f), face(f) + 3, v) != 1)
        return fail_with(why, "vertex " + name(v) + " lists face " + std::to_string(f) + " it is no corner of");
    }
    load_corners(v, fan);
    const bool closed = order_fan(fan, ordered, successor);
    if (ordered.size() != fan.size()) return fail_with(why, "vertex " + name(v) + " is non-manifold (several fans)");
    if (!in_fan_order(faces_of(record), ordered, closed))
      return fail_with(why, "vertex " + name(v) + " does not list its faces in fan order");
    if (record.active_pos >= active_.size() || active_[record.active_pos] != v)
      return fail_with(why, "vertex " + name(v) + " is missing from the active list");
    for (uint32_t a = h.parent(v); a != kNone; a = h.parent(a))
      if (is_active(a))
        return fail_with(why, "vertex " + name(v) + " and its ancestor " + name(a) + " are both active");
  }
  if (active_count != active_.size()) return fail_with(why, "active list has stale entries");
  if (!pool_blocks_disjoint(blocks)) return fail_with(why, "face-list pool blocks overlap or run past the pool");

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
