// Mutable connectivity for simplification: triangles as index triples plus, per vertex, a singly
// linked list of its corners (corner c = 3 * face + slot). Dead faces are unlinked lazily while
// walking, so a half-edge collapse costs O(valence) and nothing is allocated per vertex.
#pragma once
#include <cstdint>
#include <vector>

#include "builder/quadric.h"
#include "common/huge_pages.h"
#include "io/mesh.h"

namespace pms {

// What check_collapse() found out about a valid half-edge collapse t -> u.
struct CollapseSite {
  uint32_t face_l = UINT32_MAX;  // face (t, u, l): holds the directed edge t->u
  uint32_t face_r = UINT32_MAX;  // face (u, t, r): holds u->t
  uint32_t l = UINT32_MAX, r = UINT32_MAX;
};

// Marks for neighbour sets, one word per vertex w: the set's stamp above two bits for the directed
// edges between w and the set's centre v, so marking a neighbour costs one cache line, not two.
// One per thread.
struct NeighbourScratch {
  static constexpr uint32_t kFromCentre = 1, kToCentre = 2, kEdgeBits = kFromCentre | kToCentre;
  std::vector<uint32_t> mark;
  uint32_t stamp = 0;  // the current set's, a multiple of 4
  void resize(size_t vertices) { mark.assign(vertices, 0), stamp = 0; }
  uint32_t next();
  bool in_set(uint32_t w) const { return (mark[w] & ~kEdgeBits) == stamp; }
  bool has(uint32_t w, uint32_t edge) const { return in_set(w) && (mark[w] & edge); }
  bool both_edges(uint32_t w) const { return (mark[w] & kEdgeBits) == kEdgeBits; }
  // Puts w in the set with `edge`; returns whether it was new.
  bool add(uint32_t w, uint32_t edge) {
    uint32_t& m = mark[w];
    const bool added = (m & ~kEdgeBits) != stamp;
    m = (added ? stamp : m) | edge;
    return added;
  }
};

class CollapseMesh {
 public:
  // Plane quadrics weighted by area; boundary edges add a perpendicular plane so borders keep their shape.
  explicit CollapseMesh(const Mesh& mesh);

  uint32_t vertex_count() const { return uint32_t(head_.size()); }
  uint32_t alive_vertex_count() const { return alive_vertices_; }
  bool alive(uint32_t v) const { return vertex_alive_[v] != 0; }
  const float* position(uint32_t v) const { return &positions_[3 * size_t(v)]; }
  const Quadric& quadric(uint32_t v) const { return quadrics_[v]; }
  const uint32_t* face(uint32_t f) const { return &faces_[3 * size_t(f)]; }
  uint32_t original_corner(uint32_t corner) const { return original_[corner]; }
  uint32_t face_count() const { return uint32_t(face_alive_.size()); }
  bool face_alive(uint32_t f) const { return face_alive_[f] != 0; }

  // Starts loading what check_collapse(v, ...) reads first.
  void prefetch(uint32_t v) const {
    __builtin_prefetch(&head_[v]);
    __builtin_prefetch(&quadrics_[v]);
    __builtin_prefetch(&positions_[3 * size_t(v)]);
  }
  // The second step, once head_[v] is in cache: the first corner of v's fan.
  void prefetch_fan(uint32_t v) const {
    const uint32_t c = head_[v];
    if (c == kEnd) return;
    __builtin_prefetch(&next_corner_[c]);
    __builtin_prefetch(&faces_[c - c % 3]);
  }

  // Live faces around v (unlinks dead ones on the way).
  template <class Fn>
  void for_each_face(uint32_t v, Fn&& fn);

  // Live faces around v without unlinking dead ones: safe from several threads at once.
  template <class Fn>
  void for_each_live_face(uint32_t v, Fn&& fn) const;

  // Neighbours of v, each once, into `out`; returns whether v lies on the boundary.
  bool neighbours(uint32_t v, std::vector<uint32_t>& out) { return neighbours(v, out, scratch_marks_); }
  bool neighbours(uint32_t v, std::vector<uint32_t>& out, NeighbourScratch& scratch) const;

  // Topological and geometric validity of collapsing t into u (link condition, boundary rules,
  // no vertex left with a degenerate fan, no face flipped or made degenerate).
  bool check_collapse(uint32_t t, uint32_t u, CollapseSite& site);

  // Performs a collapse that check_collapse() accepted.
  void collapse(uint32_t t, uint32_t u, const CollapseSite& site);

  // Renumbers the live vertices 0.. in their current order and drops dead faces, so later rounds
  // walk dense arrays (a big mesh's survivors are otherwise scattered over gigabytes).
  // new_index[old vertex] = new vertex, or UINT32_MAX for a dead one.
  void compact(std::vector<uint32_t>& new_index);

 private:
  bool has_two_live_faces(uint32_t v) const;
  std::vector<uint32_t> vertices_with_boundary_edge() const;

  static constexpr uint32_t kEnd = UINT32_MAX;
  BigVector<float> positions_;
  BigVector<uint32_t> faces_;
  BigVector<uint32_t> original_;  // input corners, never modified: the dual view of every face
  BigVector<uint8_t> face_alive_;
  BigVector<uint32_t> next_corner_;
  BigVector<uint32_t> head_;  // first corner of each vertex; kEnd once the vertex is gone
  BigVector<uint8_t> vertex_alive_;
  BigVector<Quadric> quadrics_;
  uint32_t alive_vertices_ = 0;
  NeighbourScratch scratch_marks_;
  std::vector<uint32_t> scratch_;
};

template <class Fn>
void CollapseMesh::for_each_live_face(uint32_t v, Fn&& fn) const {
  for (uint32_t c = head_[v]; c != kEnd; c = next_corner_[c])
    if (face_alive_[c / 3]) fn(c / 3, c % 3);
}

template <class Fn>
void CollapseMesh::for_each_face(uint32_t v, Fn&& fn) {
  uint32_t prev = kEnd;
  for (uint32_t c = head_[v]; c != kEnd;) {
    const uint32_t next = next_corner_[c];
    const uint32_t f = c / 3;
    if (!face_alive_[f]) {
      if (prev == kEnd) head_[v] = next;
      else next_corner_[prev] = next;
    } else {
      fn(f, c - 3 * f);
      prev = c;
    }
    c = next;
  }
}

}  // namespace pms
