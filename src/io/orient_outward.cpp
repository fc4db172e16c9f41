// Closed components wound inside out are turned outward (io/orient_outward.h). Linear in the mesh, plus one
// ray per inside-out component against the other closed components' faces.
#include "io/orient_outward.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <numeric>
#include <utility>
#include <vector>

namespace pms {
namespace {

constexpr uint32_t kNone = UINT32_MAX;

uint32_t find_root(std::vector<uint32_t>& parent, uint32_t f) {
  while (parent[f] != f) f = parent[f] = parent[parent[f]];
  return f;
}

struct Components {
  std::vector<uint32_t> of_face;  // component index per face
  std::vector<uint8_t> closed;    // per component, once mark_closed() has run
  size_t count = 0;
};

// Faces joined through their vertices: in an oriented 2-manifold every vertex's faces are one fan, so
// faces that share a vertex are joined across edges too, and these are the edge-connected components.
Components find_components(const Mesh& mesh) {
  std::vector<uint32_t> parent(mesh.vertex_count());
  std::iota(parent.begin(), parent.end(), 0u);
  for (size_t f = 0; f < mesh.face_count(); ++f)
    for (size_t c = 3 * f + 1; c < 3 * f + 3; ++c) {
      const uint32_t x = find_root(parent, mesh.indices[3 * f]), y = find_root(parent, mesh.indices[c]);
      if (x != y) parent[std::max(x, y)] = std::min(x, y);
    }
  Components result;
  result.of_face.resize(mesh.face_count());
  std::vector<uint32_t> index_of_root(parent.size(), kNone);
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    const uint32_t root = find_root(parent, mesh.indices[3 * f]);
    if (index_of_root[root] == kNone) index_of_root[root] = uint32_t(result.count++);
    result.of_face[f] = index_of_root[root];
  }
  return result;
}

// A component with a boundary vertex is open. In an oriented manifold a vertex's faces (v, a, b) make one
// fan: closed, the a's and the b's are the same ring of neighbours; open, a chain w0 .. wk whose a's and
// b's differ by its two distinct ends. So a vertex is on the boundary exactly when the sum of its a's
// differs from the sum of its b's, which takes one pass over the corners and no lookups.
void mark_closed(const Mesh& mesh, Components& components) {
  const std::vector<uint32_t>& idx = mesh.indices;
  std::vector<uint64_t> next_minus_previous(mesh.vertex_count(), 0);  // modulo 2^64: |w0 - wk| < 2^32
  for (size_t f = 0; f < mesh.face_count(); ++f)
    for (size_t k = 0; k < 3; ++k)
      next_minus_previous[idx[3 * f + k]] += uint64_t(idx[3 * f + (k + 1) % 3]) - idx[3 * f + (k + 2) % 3];
  components.closed.assign(components.count, 1);
  for (size_t f = 0; f < mesh.face_count(); ++f)
    for (size_t c = 3 * f; c < 3 * f + 3; ++c)
      if (next_minus_previous[idx[c]] != 0) components.closed[components.of_face[f]] = 0;
}

using Point = std::array<double, 3>;

Point position(const Mesh& mesh, uint32_t v) {
  return {mesh.positions[3 * size_t(v)], mesh.positions[3 * size_t(v) + 1], mesh.positions[3 * size_t(v) + 2]};
}

Point sub(const Point& a, const Point& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
Point cross(const Point& a, const Point& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double dot(const Point& a, const Point& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

// Six times the signed volume each component encloses, measured from one of its own vertices (a closed
// surface's volume does not depend on the origin; a near one keeps the products small).
std::vector<double> signed_volumes(const Mesh& mesh, const Components& components) {
  std::vector<double> volume(components.count, 0);
  std::vector<Point> origin(components.count);
  std::vector<uint8_t> has_origin(components.count, 0);
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    const uint32_t k = components.of_face[f];
    if (!has_origin[k]) {
      origin[k] = position(mesh, mesh.indices[3 * f]);
      has_origin[k] = 1;
    }
    const Point a = sub(position(mesh, mesh.indices[3 * f]), origin[k]);
    const Point b = sub(position(mesh, mesh.indices[3 * f + 1]), origin[k]);
    const Point c = sub(position(mesh, mesh.indices[3 * f + 2]), origin[k]);
    volume[k] += dot(a, cross(b, c));
  }
  return volume;
}

// Whether the ray from p along a fixed direction crosses face f (Moller-Trumbore). The direction has no
// simple ratios, so a ray through an edge or a vertex of a real scan is vanishingly rare.
bool ray_crosses(const Mesh& mesh, size_t f, const Point& p) {
  static constexpr Point kDirection = {0.5736, 0.6183, 0.5373};
  const Point a = position(mesh, mesh.indices[3 * f]);
  const Point e1 = sub(position(mesh, mesh.indices[3 * f + 1]), a);
  const Point e2 = sub(position(mesh, mesh.indices[3 * f + 2]), a);
  const Point h = cross(kDirection, e2);
  const double det = dot(e1, h);
  if (det == 0) return false;
  const Point s = sub(p, a);
  const double u = dot(s, h) / det;
  if (u < 0 || u > 1) return false;
  const Point q = cross(s, e1);
  const double v = dot(kDirection, q) / det;
  if (v < 0 || u + v > 1) return false;
  return dot(e2, q) / det > 0;
}

struct Box {
  Point lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  bool contains(const Point& p) const {
    return p[0] >= lo[0] && p[0] <= hi[0] && p[1] >= lo[1] && p[1] <= hi[1] && p[2] >= lo[2] && p[2] <= hi[2];
  }
};

// Per closed component, how many other closed components enclose it (the parity of the crossings of a ray
// from one of its vertices with each), testing only the components whose bounding box holds that vertex.
std::vector<size_t> enclosures(const Mesh& mesh, const Components& components) {
  std::vector<uint32_t> start(components.count + 1, 0), faces(mesh.face_count());
  for (uint32_t k : components.of_face) ++start[k + 1];
  std::partial_sum(start.begin(), start.end(), start.begin());
  std::vector<uint32_t> cursor(start.begin(), start.end() - 1);
  for (uint32_t f = 0; f < mesh.face_count(); ++f) faces[cursor[components.of_face[f]]++] = f;
  std::vector<Box> box(components.count);
  for (uint32_t f = 0; f < mesh.face_count(); ++f)
    for (size_t c = 3 * size_t(f); c < 3 * size_t(f) + 3; ++c) {
      const Point p = position(mesh, mesh.indices[c]);
      Box& b = box[components.of_face[f]];
      for (int i = 0; i < 3; ++i) b.lo[i] = std::min(b.lo[i], p[i]), b.hi[i] = std::max(b.hi[i], p[i]);
    }
  std::vector<size_t> count(components.count, 0);
  for (uint32_t k = 0; k < components.count; ++k) {
    if (!components.closed[k]) continue;
    const Point p = position(mesh, mesh.indices[3 * size_t(faces[start[k]])]);
    for (uint32_t j = 0; j < components.count; ++j) {
      if (j == k || !components.closed[j] || !box[j].contains(p)) continue;
      bool odd = false;
      for (uint32_t i = start[j]; i < start[j + 1]; ++i) odd ^= ray_crosses(mesh, faces[i], p);
      count[k] += odd;
    }
  }
  return count;
}

}  // namespace

OutwardReport orient_closed_components_outward(Mesh& mesh) {
  OutwardReport report;
  Components components = find_components(mesh);
  const std::vector<double> volume = signed_volumes(mesh, components);
  // Only a negative volume needs the edges looked at (usually no component has one).
  if (std::none_of(volume.begin(), volume.end(), [](double v) { return v < 0; })) return report;
  mark_closed(mesh, components);
  bool inside_out = false;  // some closed component with a negative volume
  for (uint32_t k = 0; k < components.count; ++k) inside_out |= components.closed[k] && volume[k] < 0;
  if (!inside_out) return report;
  const std::vector<size_t> enclosing = enclosures(mesh, components);
  std::vector<uint8_t> turn(components.count, 0);
  for (uint32_t k = 0; k < components.count; ++k) {
    // Outside every other wall, or inside an even number: faces out (positive volume); else a cavity's wall.
    const bool faces_out = enclosing[k] % 2 == 0;
    if (components.closed[k] && volume[k] != 0 && (volume[k] > 0) != faces_out) {
      turn[k] = 1;
      ++report.components;
    }
  }
  if (report.components == 0) return report;
  std::vector<uint8_t> turned_vertex(mesh.vertex_count(), 0);
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    if (!turn[components.of_face[f]]) continue;
    std::swap(mesh.indices[3 * f + 1], mesh.indices[3 * f + 2]);
    ++report.faces;
    for (size_t c = 3 * f; c < 3 * f + 3; ++c) turned_vertex[mesh.indices[c]] = 1;
  }
  // In vertex order: each normal once, and the array read front to back rather than face by face.
  if (mesh.has_normals())
    for (size_t v = 0; v < mesh.vertex_count(); ++v)
      if (turned_vertex[v])
        for (size_t i = 0; i < 3; ++i) mesh.normals[3 * v + i] = -mesh.normals[3 * v + i];
  return report;
}

}  // namespace pms
