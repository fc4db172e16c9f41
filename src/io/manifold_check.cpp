// The builder's input contract, checked per vertex in linear time: the faces around a vertex v are
// (v, a, b) triples, i.e. link edges a -> b. The vertex is manifold when those link edges form one
// simple chain or one simple cycle; "every directed edge once" is "every link vertex left at most once".
#include "io/manifold_check.h"

#include <string>
#include <vector>

namespace pms {
namespace {

constexpr uint32_t kNoStart = UINT32_MAX;

uint32_t next_corner(uint32_t c) { return c % 3 == 2 ? c - 2 : c + 1; }
uint32_t prev_corner(uint32_t c) { return c % 3 == 0 ? c + 2 : c - 1; }

bool fail_with(std::string* why, const std::string& text) {
  if (why) *why = text;
  return false;
}

std::string vertex_name(uint32_t v) { return "vertex " + std::to_string(v); }

bool check_faces(const Mesh& mesh, std::string* why) {
  if (mesh.positions.size() % 3 != 0) return fail_with(why, "position count is not a multiple of 3");
  if (mesh.indices.size() % 3 != 0) return fail_with(why, "index count is not a multiple of 3");
  const size_t n = mesh.vertex_count();
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    const uint32_t* t = &mesh.indices[3 * f];
    auto face = [&](const char* problem) { return fail_with(why, "face " + std::to_string(f) + problem); };
    if (t[0] >= n || t[1] >= n || t[2] >= n) return face(" uses a vertex out of range");
    if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0]) return face(" repeats a corner");
    if (has_zero_area(mesh, f)) return face(" has zero area");
  }
  return true;
}

}  // namespace

bool has_zero_area(const Mesh& mesh, size_t f) {
  const uint32_t* t = &mesh.indices[3 * f];
  const float* a = &mesh.positions[3 * size_t(t[0])];
  const float* b = &mesh.positions[3 * size_t(t[1])];
  const float* c = &mesh.positions[3 * size_t(t[2])];
  const double u[3] = {double(b[0]) - a[0], double(b[1]) - a[1], double(b[2]) - a[2]};
  const double w[3] = {double(c[0]) - a[0], double(c[1]) - a[1], double(c[2]) - a[2]};
  return u[1] * w[2] == u[2] * w[1] && u[2] * w[0] == u[0] * w[2] && u[0] * w[1] == u[1] * w[0];
}

bool is_oriented_manifold(const Mesh& mesh, std::string* why) {
  if (!check_faces(mesh, why)) return false;
  const std::vector<uint32_t>& idx = mesh.indices;
  const uint32_t n = uint32_t(mesh.vertex_count());
  // Corners around each vertex (CSR).
  std::vector<uint32_t> offsets(size_t(n) + 1, 0), corners(idx.size());
  for (uint32_t v : idx) ++offsets[v + 1];
  for (uint32_t v = 0; v < n; ++v) offsets[v + 1] += offsets[v];
  {
    std::vector<uint32_t> fill(offsets.begin(), offsets.end() - 1);
    for (uint32_t c = 0; c < idx.size(); ++c) corners[fill[idx[c]]++] = c;
  }
  // Scratch per link vertex, valid when stamped with the current vertex + 1 (never cleared).
  std::vector<uint32_t> leaves(n, 0), entered(n, 0), walked(n, 0), link_next(n);
  for (uint32_t v = 0; v < n; ++v) {
    const uint32_t begin = offsets[v], end = offsets[v + 1], stamp = v + 1;
    if (begin == end) return fail_with(why, vertex_name(v) + " is not used by any face");
    for (uint32_t i = begin; i < end; ++i) {
      const uint32_t a = idx[next_corner(corners[i])], b = idx[prev_corner(corners[i])];
      if (leaves[a] == stamp)
        return fail_with(why, "directed edge " + std::to_string(v) + "->" + std::to_string(a) +
                                  " is used by two faces (non-manifold edge or inconsistent orientation)");
      if (leaves[b] == stamp && link_next[b] == a)  // (v, a, b) after (v, b, a)
        return fail_with(why, "duplicate faces at " + vertex_name(v));
      leaves[a] = stamp;
      link_next[a] = b;
      entered[b] = stamp;
    }
    // One chain starts where nothing enters; a cycle has no such start, so any link vertex will do.
    uint32_t start = kNoStart;
    for (uint32_t i = begin; i < end; ++i) {
      const uint32_t a = idx[next_corner(corners[i])];
      if (entered[a] == stamp) continue;
      if (start != kNoStart) return fail_with(why, vertex_name(v) + " has more than one fan");
      start = a;
    }
    if (start == kNoStart) start = idx[next_corner(corners[begin])];
    uint32_t steps = 0;
    for (uint32_t a = start; leaves[a] == stamp && walked[a] != stamp; a = link_next[a]) {
      walked[a] = stamp;
      ++steps;
    }
    if (steps != end - begin) return fail_with(why, vertex_name(v) + " has more than one fan");
  }
  return true;
}

}  // namespace pms
