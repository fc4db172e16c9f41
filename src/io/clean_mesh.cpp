// Cleaning before the build: the builder needs an oriented 2-manifold (boundaries allowed).
// Weld exactly coincident vertices, drop degenerate and duplicate faces, orient faces consistently
// (breadth-first over manifold edges), cut non-manifold edges and split non-manifold vertices by
// giving every edge-connected fan around a vertex its own copy of it.
#include <algorithm>
#include <array>
#include <cstring>
#include <numeric>
#include <vector>

#include "common/error.h"
#include "io/manifold_check.h"
#include "io/mesh.h"

namespace pms {
namespace {

// Keeps vertex attributes in step when vertices are renumbered: new vertex i takes old source[i].
void gather_vertices(Mesh& mesh, const std::vector<uint32_t>& source) {
  auto gather = [&](auto& array, size_t width) {
    if (array.empty()) return;
    std::remove_reference_t<decltype(array)> out(source.size() * width);
    for (size_t i = 0; i < source.size(); ++i)
      std::copy_n(&array[source[i] * width], width, &out[i * width]);
    array = std::move(out);
  };
  gather(mesh.positions, 3);
  gather(mesh.normals, 3);
  gather(mesh.colors, 4);
}

uint32_t float_key(float f) {
  if (f == 0) f = 0;  // -0 and +0 are the same point
  uint32_t bits;
  std::memcpy(&bits, &f, 4);
  return bits;
}

void weld(Mesh& mesh, CleanReport& report) {
  const uint32_t n = uint32_t(mesh.vertex_count());
  std::vector<std::array<uint32_t, 4>> keys(n);
  for (uint32_t i = 0; i < n; ++i)
    keys[i] = {float_key(mesh.positions[3 * size_t(i)]), float_key(mesh.positions[3 * size_t(i) + 1]),
               float_key(mesh.positions[3 * size_t(i) + 2]), i};
  std::sort(keys.begin(), keys.end());
  std::vector<uint32_t> representative(n);
  for (uint32_t i = 0; i < n; ++i) {
    const bool same = i > 0 && std::equal(keys[i].begin(), keys[i].begin() + 3, keys[i - 1].begin());
    representative[keys[i][3]] = same ? representative[keys[i - 1][3]] : keys[i][3];
  }
  std::vector<uint32_t> new_index(n), source;
  for (uint32_t i = 0; i < n; ++i) {
    if (representative[i] == i) {
      new_index[i] = uint32_t(source.size());
      source.push_back(i);
    } else {
      new_index[i] = new_index[representative[i]];  // the first of a group has the lowest index
    }
  }
  report.welded_vertices = n - source.size();
  if (report.welded_vertices == 0) return;
  for (uint32_t& v : mesh.indices) v = new_index[v];
  gather_vertices(mesh, source);
}

bool zero_area(const Mesh& mesh, const uint32_t* t) {
  const float* a = &mesh.positions[3 * size_t(t[0])];
  const float* b = &mesh.positions[3 * size_t(t[1])];
  const float* c = &mesh.positions[3 * size_t(t[2])];
  const double u[3] = {double(b[0]) - a[0], double(b[1]) - a[1], double(b[2]) - a[2]};
  const double w[3] = {double(c[0]) - a[0], double(c[1]) - a[1], double(c[2]) - a[2]};
  return u[1] * w[2] - u[2] * w[1] == 0 && u[2] * w[0] - u[0] * w[2] == 0 && u[0] * w[1] - u[1] * w[0] == 0;
}

void drop_bad_faces(Mesh& mesh, CleanReport& report) {
  const size_t m = mesh.face_count();
  std::vector<uint8_t> keep(m, 1);
  std::vector<std::array<uint32_t, 4>> sorted;
  sorted.reserve(m);
  for (size_t f = 0; f < m; ++f) {
    const uint32_t* t = &mesh.indices[3 * f];
    if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0] || zero_area(mesh, t)) {
      keep[f] = 0;
      ++report.degenerate_faces;
      continue;
    }
    std::array<uint32_t, 4> key{t[0], t[1], t[2], uint32_t(f)};
    std::sort(key.begin(), key.begin() + 3);
    sorted.push_back(key);
  }
  std::sort(sorted.begin(), sorted.end());
  for (size_t i = 1; i < sorted.size(); ++i)
    if (std::equal(sorted[i].begin(), sorted[i].begin() + 3, sorted[i - 1].begin())) {
      keep[sorted[i][3]] = 0;  // sorted by face index within equal corners: the first one stays
      ++report.duplicate_faces;
    }
  size_t out = 0;
  for (size_t f = 0; f < m; ++f)
    if (keep[f]) std::copy_n(&mesh.indices[3 * f], 3, &mesh.indices[3 * out++]);
  mesh.indices.resize(3 * out);
}

struct UnionFind {
  std::vector<uint32_t> parent;
  explicit UnionFind(size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0u); }
  uint32_t find(uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void join(uint32_t a, uint32_t b) { parent[find(a)] = find(b); }
};

uint32_t corner_of(const Mesh& mesh, uint32_t face, uint32_t v) {
  const uint32_t* t = &mesh.indices[3 * size_t(face)];
  return 3 * face + (t[0] == v ? 0 : t[1] == v ? 1 : 2);
}

// Two faces glued along an undirected edge; `same_direction` = both hold lo->hi (or both hi->lo).
struct Glue {
  uint32_t face_a, face_b, lo, hi;
  bool same_direction;
  bool cut;
};

// One pass of orientation + manifold repair; returns whether anything was cut or split.
bool repair_manifold(Mesh& mesh, CleanReport& report) {
  const uint32_t m = uint32_t(mesh.face_count());
  struct EdgeUse {
    uint32_t lo, hi, face;
    bool forward;  // the face holds lo->hi
  };
  std::vector<EdgeUse> uses;
  uses.reserve(3 * size_t(m));
  for (uint32_t f = 0; f < m; ++f)
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = mesh.indices[3 * size_t(f) + k], b = mesh.indices[3 * size_t(f) + (k + 1) % 3];
      uses.push_back({std::min(a, b), std::max(a, b), f, a < b});
    }
  std::sort(uses.begin(), uses.end(), [](const EdgeUse& x, const EdgeUse& y) {
    return x.lo < y.lo || (x.lo == y.lo && (x.hi < y.hi || (x.hi == y.hi && x.face < y.face)));
  });
  std::vector<Glue> glues;
  std::vector<uint8_t> isolated(3 * size_t(m), 0);  // corner kept apart from every fan at its vertex
  bool changed = false;
  for (size_t i = 0; i < uses.size();) {
    size_t j = i;
    while (j < uses.size() && uses[j].lo == uses[i].lo && uses[j].hi == uses[i].hi) ++j;
    const size_t count = j - i;
    if (count >= 2) {
      // Keep an oppositely oriented pair if there is one; every other face is cut off this edge.
      size_t second = i + 1;
      for (size_t k = i + 1; k < j; ++k)
        if (uses[k].forward != uses[i].forward) { second = k; break; }
      glues.push_back({uses[i].face, uses[second].face, uses[i].lo, uses[i].hi,
                       uses[i].forward == uses[second].forward, false});
      for (size_t k = i + 1; k < j; ++k) {
        if (k == second) continue;
        isolated[corner_of(mesh, uses[k].face, uses[k].lo)] = 1;
        isolated[corner_of(mesh, uses[k].face, uses[k].hi)] = 1;
      }
      if (count > 2) {
        ++report.nonmanifold_edges;
        changed = true;
      }
    }
    i = j;
  }

  // Orient breadth-first across glued edges; an inconsistent glue (non-orientable) is cut.
  std::vector<uint32_t> offsets(m + 1, 0), adjacent(2 * glues.size());
  for (const Glue& g : glues) ++offsets[g.face_a + 1], ++offsets[g.face_b + 1];
  for (uint32_t f = 0; f < m; ++f) offsets[f + 1] += offsets[f];
  {
    std::vector<uint32_t> fill(offsets.begin(), offsets.end() - 1);
    for (uint32_t g = 0; g < glues.size(); ++g) {
      adjacent[fill[glues[g].face_a]++] = g;
      adjacent[fill[glues[g].face_b]++] = g;
    }
  }
  std::vector<int8_t> flip(m, -1);
  std::vector<uint32_t> queue;
  for (uint32_t seed = 0; seed < m; ++seed) {
    if (flip[seed] != -1) continue;
    queue.assign(1, seed);
    flip[seed] = 0;
    size_t flipped = 0;
    for (size_t q = 0; q < queue.size(); ++q) {
      const uint32_t f = queue[q];
      for (uint32_t a = offsets[f]; a < offsets[f + 1]; ++a) {
        Glue& g = glues[adjacent[a]];
        if (g.cut) continue;
        const uint32_t other = g.face_a == f ? g.face_b : g.face_a;
        const int8_t wanted = int8_t(flip[f] ^ int8_t(g.same_direction));
        if (flip[other] == -1) {
          flip[other] = wanted;
          flipped += size_t(wanted);
          queue.push_back(other);
        } else if (flip[other] != wanted) {
          g.cut = true;
          isolated[corner_of(mesh, other, g.lo)] = 1;
          isolated[corner_of(mesh, other, g.hi)] = 1;
          ++report.nonmanifold_edges;
          changed = true;
        }
      }
    }
    if (2 * flipped > queue.size())  // keep the orientation most of the component already had
      for (uint32_t f : queue) flip[f] ^= 1;
  }
  for (uint32_t f = 0; f < m; ++f)
    if (flip[f] == 1) {
      std::swap(mesh.indices[3 * size_t(f) + 1], mesh.indices[3 * size_t(f) + 2]);
      ++report.flipped_faces;
    }

  // Fans: corners at the same vertex joined across glued edges; each extra fan gets a copy.
  UnionFind fans(3 * size_t(m));
  for (const Glue& g : glues) {
    if (g.cut) continue;
    for (uint32_t v : {g.lo, g.hi}) {
      const uint32_t ca = corner_of(mesh, g.face_a, v), cb = corner_of(mesh, g.face_b, v);
      if (!isolated[ca] && !isolated[cb]) fans.join(ca, cb);
    }
  }
  const uint32_t n = uint32_t(mesh.vertex_count());
  std::vector<uint32_t> vertex_of_root(3 * size_t(m), UINT32_MAX), source(n);
  std::iota(source.begin(), source.end(), 0u);
  std::vector<uint8_t> claimed(n, 0), counted(n, 0);
  for (uint32_t c = 0; c < 3 * m; ++c) {
    const uint32_t v = mesh.indices[c], root = fans.find(c);
    if (vertex_of_root[root] == UINT32_MAX) {
      if (!claimed[v]) {
        claimed[v] = 1;
        vertex_of_root[root] = v;
      } else {
        vertex_of_root[root] = uint32_t(source.size());
        source.push_back(v);
        ++report.split_vertex_copies;
        if (!counted[v]) counted[v] = 1, ++report.nonmanifold_vertices;
        changed = true;
      }
    }
    mesh.indices[c] = vertex_of_root[root];
  }
  if (source.size() > n) gather_vertices(mesh, source);
  return changed;
}

void drop_unreferenced(Mesh& mesh, CleanReport& report) {
  const size_t n = mesh.vertex_count();
  std::vector<uint32_t> new_index(n, UINT32_MAX), source;
  for (uint32_t v : mesh.indices) new_index[v] = 0;
  for (uint32_t v = 0; v < n; ++v)
    if (new_index[v] == 0) {
      new_index[v] = uint32_t(source.size());
      source.push_back(v);
    }
  report.unreferenced_vertices = n - source.size();
  if (source.size() == n) return;
  for (uint32_t& v : mesh.indices) v = new_index[v];
  gather_vertices(mesh, source);
}

}  // namespace

CleanReport clean_mesh(Mesh& mesh) {
  CleanReport report;
  weld(mesh, report);
  drop_bad_faces(mesh, report);
  drop_unreferenced(mesh, report);
  if (mesh.face_count() == 0) fail("", "no faces left after cleaning");
  // Most scans are already oriented manifolds: checking is cheaper than repairing.
  if (is_oriented_manifold(mesh)) return report;
  // A cut can expose another problem at the new copies; a few passes settle every case seen.
  for (int pass = 0; pass < 4 && repair_manifold(mesh, report); ++pass) {
  }
  std::string why;
  if (!is_oriented_manifold(mesh, &why)) fail("", "could not repair the mesh into an oriented manifold: " + why);
  return report;
}

}  // namespace pms
