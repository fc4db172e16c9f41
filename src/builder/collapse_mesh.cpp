#include "builder/collapse_mesh.h"

#include <cmath>

#include "common/error.h"
#include "common/parallel.h"

namespace pms {
namespace {

struct Vec3 {
  double x, y, z;
};
Vec3 sub(const float* a, const float* b) { return {double(a[0]) - b[0], double(a[1]) - b[1], double(a[2]) - b[2]}; }
Vec3 cross(Vec3 a, Vec3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
double dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

Vec3 triangle_normal(const float* a, const float* b, const float* c) { return cross(sub(b, a), sub(c, a)); }

// Boundary weight relative to the area-weighted face planes: strong enough that open borders
// (scan holes, terrain edges) survive until late in the simplification.
constexpr double kBoundaryWeight = 8.0;

}  // namespace

CollapseMesh::CollapseMesh(const Mesh& mesh)
    : positions_(mesh.positions.begin(), mesh.positions.end()),
      faces_(mesh.indices.begin(), mesh.indices.end()),
      original_(mesh.indices.begin(), mesh.indices.end()),
      face_alive_(mesh.face_count(), 1),
      next_corner_(mesh.indices.size(), kEnd),
      head_(mesh.vertex_count(), kEnd),
      vertex_alive_(mesh.vertex_count(), 1),
      quadrics_(mesh.vertex_count()),
      alive_vertices_(uint32_t(mesh.vertex_count())),
      scratch_marks_() {
  scratch_marks_.resize(mesh.vertex_count());
  if (mesh.vertex_count() >= kEnd / 2 || mesh.indices.size() >= kEnd) fail("", "mesh too large for 32-bit indices");
  for (size_t c = faces_.size(); c-- > 0;) {
    const uint32_t v = faces_[c];
    next_corner_[c] = head_[v];
    head_[v] = uint32_t(c);
  }
  for (size_t f = 0; f < face_alive_.size(); ++f) {
    const uint32_t* t = face(uint32_t(f));
    const Vec3 n = triangle_normal(position(t[0]), position(t[1]), position(t[2]));
    const double len = std::sqrt(dot(n, n));
    if (len == 0) continue;
    const Vec3 unit{n.x / len, n.y / len, n.z / len};
    const float* p = position(t[0]);
    const Quadric q =
        Quadric::plane(unit.x, unit.y, unit.z, -(unit.x * p[0] + unit.y * p[1] + unit.z * p[2]), len * 0.5);
    for (int k = 0; k < 3; ++k) quadrics_[t[k]] += q;
  }
  // A directed edge v->a is on the boundary when no face holds a->v. Finding the vertices with one
  // reads every fan and runs on all cores; their quadrics are then added in vertex order, as ever.
  for (const uint32_t v : vertices_with_boundary_edge()) {
    NeighbourScratch& marks = scratch_marks_;
    marks.next();
    for_each_live_face(v, [&](uint32_t f, uint32_t slot) {
      const uint32_t b = faces_[3 * f + (slot + 2) % 3];
      marks.add(b, NeighbourScratch::kToCentre);
    });
    for_each_live_face(v, [&](uint32_t f, uint32_t slot) {
      const uint32_t a = faces_[3 * f + (slot + 1) % 3];
      if (marks.has(a, NeighbourScratch::kToCentre)) return;
      const Vec3 edge = sub(position(a), position(v));
      const uint32_t* t = face(f);
      const Vec3 n = triangle_normal(position(t[0]), position(t[1]), position(t[2]));
      Vec3 side = cross(edge, n);
      const double len = std::sqrt(dot(side, side));
      if (len == 0) return;
      side = {side.x / len, side.y / len, side.z / len};
      const float* p = position(v);
      const Quadric q = Quadric::plane(side.x, side.y, side.z, -(side.x * p[0] + side.y * p[1] + side.z * p[2]),
                                       kBoundaryWeight * dot(edge, edge));
      quadrics_[v] += q;
      quadrics_[a] += q;
    });
  }
}

std::vector<uint32_t> CollapseMesh::vertices_with_boundary_edge() const {
  const uint32_t n = vertex_count();
  std::vector<uint8_t> has_boundary_edge(n, 0);
  for_each_range(n, 1 << 14, [&](size_t begin, size_t end) {
    NeighbourScratch marks;
    marks.resize(n);
    std::vector<uint32_t> around;
    for (uint32_t v = uint32_t(begin); v < end; ++v) has_boundary_edge[v] = neighbours(v, around, marks);
  });
  std::vector<uint32_t> boundary;
  for (uint32_t v = 0; v < n; ++v)
    if (has_boundary_edge[v]) boundary.push_back(v);
  return boundary;
}

uint32_t NeighbourScratch::next() {
  stamp += kEdgeBits + 1;
  if (stamp == 0) {  // wrapped: clear so stale marks cannot match
    std::fill(mark.begin(), mark.end(), 0);
    stamp = kEdgeBits + 1;
  }
  return stamp;
}

bool CollapseMesh::neighbours(uint32_t v, std::vector<uint32_t>& out, NeighbourScratch& marks) const {
  out.clear();
  marks.next();
  for_each_live_face(v, [&](uint32_t f, uint32_t slot) {
    const uint32_t a = faces_[3 * f + (slot + 1) % 3];
    const uint32_t b = faces_[3 * f + (slot + 2) % 3];
    if (marks.add(a, NeighbourScratch::kFromCentre)) out.push_back(a);  // v -> a
    if (marks.add(b, NeighbourScratch::kToCentre)) out.push_back(b);    // b -> v
  });
  bool boundary = false;
  for (uint32_t n : out) boundary |= !marks.both_edges(n);
  return boundary;
}

bool CollapseMesh::has_two_live_faces(uint32_t v) const {
  // Stops at the second face: an apex's whole fan is a chain of cache misses, and only "< 2" matters.
  uint32_t faces = 0;
  for (uint32_t c = head_[v]; c != kEnd; c = next_corner_[c])
    if (face_alive_[c / 3] && ++faces == 2) return true;
  return false;
}

bool CollapseMesh::check_collapse(uint32_t t, uint32_t u, CollapseSite& site) {
  site = {};
  uint32_t t_faces = 0;
  for_each_face(t, [&](uint32_t f, uint32_t slot) {
    ++t_faces;
    const uint32_t a = faces_[3 * f + (slot + 1) % 3];
    const uint32_t b = faces_[3 * f + (slot + 2) % 3];
    if (a == u) {
      site.face_l = f;
      site.l = b;
    }
    if (b == u) {
      site.face_r = f;
      site.r = a;
    }
  });
  const bool has_l = site.face_l != UINT32_MAX, has_r = site.face_r != UINT32_MAX;
  if (!has_l && !has_r) return false;  // not an edge
  if (has_l && has_r && site.l == site.r) return false;

  // Boundary rule: a boundary vertex may only slide along a boundary edge.
  const bool t_boundary = neighbours(t, scratch_);
  const bool edge_boundary = !(has_l && has_r);
  if (t_boundary && !edge_boundary) return false;
  const uint32_t t_valence = uint32_t(scratch_.size());

  // Link condition: the only common neighbours of t and u are the apexes of the edge's faces.
  // neighbours(t) left N(t) marked with the current stamp.
  bool link_ok = true;
  uint32_t u_valence_faces = 0;
  for_each_face(u, [&](uint32_t f, uint32_t slot) {
    ++u_valence_faces;
    for (uint32_t k = 1; k <= 2; ++k) {
      const uint32_t w = faces_[3 * f + (slot + k) % 3];
      if (w != t && scratch_marks_.in_set(w) && w != site.l && w != site.r) link_ok = false;
    }
  });
  if (!link_ok) return false;
  // A closed tetrahedron would fold into two coincident triangles.
  if (!t_boundary && t_valence == 3 && t_faces == 3 && u_valence_faces == 3) return false;
  // Each apex must keep at least one face.
  for (uint32_t apex : {site.l, site.r})
    if (apex != UINT32_MAX && !has_two_live_faces(apex)) return false;

  // Geometry: moving t onto u must not flip or flatten any surviving face around t.
  const float* pu = position(u);
  bool geometry_ok = true;
  for_each_face(t, [&](uint32_t f, uint32_t slot) {
    if (f == site.face_l || f == site.face_r || !geometry_ok) return;
    const float* pa = position(faces_[3 * f + (slot + 1) % 3]);
    const float* pb = position(faces_[3 * f + (slot + 2) % 3]);
    const Vec3 before = triangle_normal(position(t), pa, pb);
    const Vec3 after = triangle_normal(pu, pa, pb);
    const double after_len2 = dot(after, after);
    if (dot(before, after) <= 0 || after_len2 <= 1e-12 * dot(before, before)) geometry_ok = false;
  });
  return geometry_ok;
}

void CollapseMesh::compact(std::vector<uint32_t>& new_index) {
  const uint32_t n = vertex_count();
  new_index.assign(n, UINT32_MAX);
  uint32_t live = 0;
  for (uint32_t v = 0; v < n; ++v)
    if (vertex_alive_[v]) {
      new_index[v] = live;
      std::copy_n(&positions_[3 * size_t(v)], 3, &positions_[3 * size_t(live)]);
      quadrics_[live] = quadrics_[v];
      ++live;
    }
  positions_.resize(3 * size_t(live));
  quadrics_.resize(live);
  vertex_alive_.assign(live, 1);
  size_t kept = 0;
  for (size_t f = 0; f < face_alive_.size(); ++f) {
    if (!face_alive_[f]) continue;
    for (int k = 0; k < 3; ++k) {
      faces_[3 * kept + k] = new_index[faces_[3 * f + k]];
      original_[3 * kept + k] = original_[3 * f + k];
    }
    ++kept;
  }
  faces_.resize(3 * kept);
  original_.resize(3 * kept);
  face_alive_.assign(kept, 1);
  next_corner_.assign(3 * kept, kEnd);
  head_.assign(live, kEnd);
  for (size_t c = faces_.size(); c-- > 0;) {
    next_corner_[c] = head_[faces_[c]];
    head_[faces_[c]] = uint32_t(c);
  }
  scratch_marks_.resize(live);
}

void CollapseMesh::collapse(uint32_t t, uint32_t u, const CollapseSite& site) {
  if (site.face_l != UINT32_MAX) face_alive_[site.face_l] = 0;
  if (site.face_r != UINT32_MAX) face_alive_[site.face_r] = 0;
  uint32_t last = kEnd;
  for (uint32_t c = head_[t]; c != kEnd; c = next_corner_[c]) {
    faces_[c] = u;
    last = c;
  }
  if (last != kEnd) {
    next_corner_[last] = head_[u];
    head_[u] = head_[t];
  }
  head_[t] = kEnd;
  vertex_alive_[t] = 0;
  quadrics_[u] += quadrics_[t];
  --alive_vertices_;
}

}  // namespace pms
