#include "io/manifold_check.h"

#include <algorithm>
#include <array>
#include <vector>

namespace pms {
namespace {

bool fail_with(std::string* why, std::string text) {
  if (why) *why = std::move(text);
  return false;
}

// Vertex -> incident faces as CSR.
void vertex_faces(const Mesh& mesh, std::vector<uint32_t>& offsets, std::vector<uint32_t>& faces) {
  const size_t n = mesh.vertex_count();
  offsets.assign(n + 1, 0);
  for (uint32_t v : mesh.indices) ++offsets[v + 1];
  for (size_t i = 0; i < n; ++i) offsets[i + 1] += offsets[i];
  faces.resize(mesh.indices.size());
  std::vector<uint32_t> fill(offsets.begin(), offsets.end() - 1);
  for (size_t c = 0; c < mesh.indices.size(); ++c) faces[fill[mesh.indices[c]]++] = uint32_t(c / 3);
}

}  // namespace

bool is_oriented_manifold(const Mesh& mesh, std::string* why) {
  const size_t n = mesh.vertex_count(), m = mesh.face_count();
  if (mesh.indices.size() % 3 != 0) return fail_with(why, "index count is not a multiple of 3");
  for (uint32_t v : mesh.indices)
    if (v >= n) return fail_with(why, "index " + std::to_string(v) + " out of range");
  for (size_t f = 0; f < m; ++f) {
    const uint32_t* t = &mesh.indices[3 * f];
    if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0]) return fail_with(why, "face " + std::to_string(f) + " is degenerate");
  }
  std::vector<uint32_t> offsets, faces;
  vertex_faces(mesh, offsets, faces);
  // Per vertex (linear, no global sort): each outgoing edge v->a once; duplicate faces are found at
  // their smallest corner.
  std::vector<uint32_t> seen(n, 0);
  std::vector<std::pair<uint32_t, uint32_t>> others;
  for (uint32_t v = 0; v < n; ++v) {
    others.clear();
    for (uint32_t i = offsets[v]; i < offsets[v + 1]; ++i) {
      const uint32_t* t = &mesh.indices[3 * size_t(faces[i])];
      const int k = t[0] == v ? 0 : t[1] == v ? 1 : 2;
      const uint32_t a = t[(k + 1) % 3], b = t[(k + 2) % 3];
      if (seen[a] == v + 1)
        return fail_with(why, "directed edge " + std::to_string(v) + "->" + std::to_string(a) +
                                  " used twice (non-manifold edge or inconsistent orientation)");
      seen[a] = v + 1;
      if (v < a && v < b) others.push_back({std::min(a, b), std::max(a, b)});
    }
    std::sort(others.begin(), others.end());
    if (std::adjacent_find(others.begin(), others.end()) != others.end()) return fail_with(why, "duplicate faces");
  }

  // Single fan per vertex: the link edges a->b of faces (v, a, b) form one path or one cycle.
  std::vector<uint32_t> next(n, UINT32_MAX), has_in(n, 0);
  for (uint32_t v = 0; v < n; ++v) {
    const uint32_t begin = offsets[v], end = offsets[v + 1];
    if (begin == end) return fail_with(why, "vertex " + std::to_string(v) + " is not used by any face");
    for (uint32_t i = begin; i < end; ++i) {
      const uint32_t* t = &mesh.indices[3 * size_t(faces[i])];
      const int k = t[0] == v ? 0 : t[1] == v ? 1 : 2;
      next[t[(k + 1) % 3]] = t[(k + 2) % 3];
      has_in[t[(k + 2) % 3]] = v + 1;
    }
    uint32_t start = UINT32_MAX;
    for (uint32_t i = begin; i < end; ++i) {
      const uint32_t* t = &mesh.indices[3 * size_t(faces[i])];
      const int k = t[0] == v ? 0 : t[1] == v ? 1 : 2;
      const uint32_t a = t[(k + 1) % 3];
      if (has_in[a] != v + 1) {
        if (start != UINT32_MAX) return fail_with(why, "vertex " + std::to_string(v) + " has more than one fan");
        start = a;
      }
    }
    if (start == UINT32_MAX) {  // closed fan: walk the cycle from any link vertex
      const uint32_t* t = &mesh.indices[3 * size_t(faces[begin])];
      const int k = t[0] == v ? 0 : t[1] == v ? 1 : 2;
      start = t[(k + 1) % 3];
    }
    uint32_t steps = 0;
    for (uint32_t a = start; steps <= end - begin && next[a] != UINT32_MAX;) {
      const uint32_t b = next[a];
      next[a] = UINT32_MAX;
      ++steps;
      a = b;
    }
    for (uint32_t i = begin; i < end; ++i) {  // reset scratch for the next vertex
      const uint32_t* t = &mesh.indices[3 * size_t(faces[i])];
      const int k = t[0] == v ? 0 : t[1] == v ? 1 : 2;
      next[t[(k + 1) % 3]] = UINT32_MAX;
    }
    if (steps != end - begin) return fail_with(why, "vertex " + std::to_string(v) + " has more than one fan");
  }
  return true;
}

}  // namespace pms
