// Cleaning before the build: the builder needs an oriented 2-manifold with boundary (docs/internals.md, "Builder").
//  1. Weld bitwise-coincident vertices (-0 == +0) with a hash table; the first vertex's attributes win.
//  2. Drop degenerate faces (repeated corner, or a cross product that is exactly zero) and duplicate
//     faces (same corner set in any order or orientation; the first one stays).
//  3. Drop vertices no face uses. Nothing below orphans a vertex, so this is also the final compaction.
//  4. Unless the mesh already is an oriented manifold: glue at most one pair of faces along every edge
//     (preferring an oppositely oriented pair), orient each glued component breadth-first (the majority
//     orientation wins; a glue that makes a component non-orientable is cut), then give every fan of
//     glued faces around a vertex its own copy of the vertex.
//  5. Turn closed components wound inside out outward (io/orient_outward.h).
// Every step is linear or sorts only small buckets, and every choice is made in index order, so the same
// input gives the same output bit for bit. Normals, colors and texture coordinates move with their
// positions throughout; welding looks at positions only, so two coincident vertices that differ in any of
// them (an OBJ seam's copies) become one with the first one's.
#include <algorithm>
#include <array>
#include <cstring>
#include <string>
#include <vector>

#include "common/error.h"
#include "io/manifold_check.h"
#include "io/mesh.h"
#include "io/orient_outward.h"

namespace pms {
namespace {

constexpr uint32_t kNone = UINT32_MAX;

// Corner c of face c/3; "corner-edge" c is the directed edge from corner c to the next corner.
uint32_t next_corner(uint32_t c) { return c % 3 == 2 ? c - 2 : c + 1; }
uint32_t prev_corner(uint32_t c) { return c % 3 == 0 ? c + 2 : c - 1; }

// New vertex i takes old vertex source[i]'s attributes.
void gather_vertices(Mesh& mesh, const std::vector<uint32_t>& source) {
  auto gather = [&](auto& array, size_t width) {
    if (array.empty()) return;
    std::remove_reference_t<decltype(array)> out(source.size() * width);
    for (size_t i = 0; i < source.size(); ++i) std::copy_n(&array[source[i] * width], width, &out[i * width]);
    array = std::move(out);
  };
  gather(mesh.positions, 3);
  gather(mesh.normals, 3);
  gather(mesh.colors, 4);
  gather(mesh.texcoords, 2);
}

void check_input(const Mesh& mesh) {
  if (mesh.positions.size() % 3 != 0) fail("", "mesh: position count is not a multiple of 3");
  if (mesh.indices.size() % 3 != 0) fail("", "mesh: index count is not a multiple of 3");
  const size_t n = mesh.vertex_count();
  if (n >= kNone || mesh.indices.size() >= kNone) fail("", "mesh: more than 2^32 - 1 vertices or corners");
  if (mesh.has_normals() && mesh.normals.size() != mesh.positions.size())
    fail("", "mesh: normal count differs from the vertex count");
  if (mesh.has_colors() && mesh.colors.size() != 4 * n) fail("", "mesh: color count differs from the vertex count");
  if (mesh.has_texcoords() && mesh.texcoords.size() != 2 * n)
    fail("", "mesh: texture coordinate count differs from the vertex count");
  for (size_t c = 0; c < mesh.indices.size(); ++c)
    if (mesh.indices[c] >= n)
      fail("", "mesh: face " + std::to_string(c / 3) + " uses vertex " + std::to_string(mesh.indices[c]) + " of " +
                   std::to_string(n));
}

// ---- 1. Weld ----------------------------------------------------------------------------------------

using PositionKey = std::array<uint32_t, 3>;

PositionKey position_key(const Mesh& mesh, uint32_t v) {
  PositionKey key;
  for (int i = 0; i < 3; ++i) {
    float f = mesh.positions[3 * size_t(v) + i];
    if (f == 0) f = 0;  // -0 and +0 are the same point
    std::memcpy(&key[i], &f, 4);
  }
  return key;
}

uint32_t hash_key(const PositionKey& k) {
  uint32_t h = k[0] * 0x8da6b343u ^ k[1] * 0xd8163841u ^ k[2] * 0xcb1ab31fu;
  h ^= h >> 16;
  h *= 0x7feb352du;
  h ^= h >> 15;
  h *= 0x846ca68bu;
  return h ^ (h >> 16);
}

// Open addressing over vertex ids, at most 2/3 full; vertices are visited in order, so the first
// of a coincident group is the one kept and the kept vertices keep their relative order.
void weld(Mesh& mesh, CleanReport& report) {
  const uint32_t n = uint32_t(mesh.vertex_count());
  size_t capacity = 16;
  while (capacity < size_t(n) + n / 2) capacity *= 2;
  const size_t mask = capacity - 1;
  std::vector<uint32_t> table(capacity, kNone), new_index(n), source;
  source.reserve(n);
  for (uint32_t v = 0; v < n; ++v) {
    const PositionKey key = position_key(mesh, v);
    size_t slot = hash_key(key) & mask;
    while (table[slot] != kNone && position_key(mesh, table[slot]) != key) slot = (slot + 1) & mask;
    if (table[slot] == kNone) {
      table[slot] = v;
      new_index[v] = uint32_t(source.size());
      source.push_back(v);
    } else {
      new_index[v] = new_index[table[slot]];
    }
  }
  report.welded_vertices = n - source.size();
  if (report.welded_vertices == 0) return;
  for (uint32_t& v : mesh.indices) v = new_index[v];
  gather_vertices(mesh, source);
}

// ---- 2. Degenerate and duplicate faces ----------------------------------------------------------------

// Duplicates share their smallest corner: bucket faces by it (counting sort, faces in index order)
// and sort only inside the buckets, which hold a handful of faces each.
std::vector<uint8_t> find_duplicates(const Mesh& mesh, const std::vector<uint8_t>& keep, CleanReport& report) {
  const size_t n = mesh.vertex_count(), m = mesh.face_count();
  std::vector<uint32_t> offsets(n + 1, 0), bucket;
  auto smallest = [&](size_t f) {
    return std::min({mesh.indices[3 * f], mesh.indices[3 * f + 1], mesh.indices[3 * f + 2]});
  };
  for (size_t f = 0; f < m; ++f)
    if (keep[f]) ++offsets[smallest(f) + 1];
  for (size_t v = 0; v < n; ++v) offsets[v + 1] += offsets[v];
  bucket.resize(offsets[n]);
  {
    std::vector<uint32_t> fill(offsets.begin(), offsets.end() - 1);
    for (size_t f = 0; f < m; ++f)
      if (keep[f]) bucket[fill[smallest(f)]++] = uint32_t(f);
  }
  std::vector<uint8_t> duplicate(m, 0);
  std::vector<std::array<uint32_t, 3>> others;  // (middle corner, largest corner, face)
  for (size_t v = 0; v < n; ++v) {
    if (offsets[v + 1] - offsets[v] < 2) continue;
    others.clear();
    for (uint32_t i = offsets[v]; i < offsets[v + 1]; ++i) {
      const uint32_t* t = &mesh.indices[3 * size_t(bucket[i])];
      const uint32_t a = t[0] == v ? t[1] : t[0], b = t[2] == v ? t[1] : t[2];
      others.push_back({std::min(a, b), std::max(a, b), bucket[i]});
    }
    std::sort(others.begin(), others.end());
    for (size_t i = 1; i < others.size(); ++i)
      if (others[i][0] == others[i - 1][0] && others[i][1] == others[i - 1][1]) {
        duplicate[others[i][2]] = 1;  // sorted by face within equal corners: the first one stays
        ++report.duplicate_faces;
      }
  }
  return duplicate;
}

void drop_bad_faces(Mesh& mesh, CleanReport& report) {
  const size_t m = mesh.face_count();
  std::vector<uint8_t> keep(m, 1);
  for (size_t f = 0; f < m; ++f) {
    const uint32_t* t = &mesh.indices[3 * f];
    if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0] || has_zero_area(mesh, f)) {
      keep[f] = 0;
      ++report.degenerate_faces;
    }
  }
  const std::vector<uint8_t> duplicate = find_duplicates(mesh, keep, report);
  size_t out = 0;
  for (size_t f = 0; f < m; ++f)
    if (keep[f] && !duplicate[f]) std::copy_n(&mesh.indices[3 * f], 3, &mesh.indices[3 * out++]);
  mesh.indices.resize(3 * out);
}

// ---- 3. Unreferenced vertices --------------------------------------------------------------------------

void drop_unreferenced(Mesh& mesh, CleanReport& report) {
  const size_t n = mesh.vertex_count();
  std::vector<uint32_t> new_index(n, kNone), source;
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

// ---- 4. Manifold repair ----------------------------------------------------------------------------------

// Every corner-edge, grouped by undirected edge: sorted by (smaller vertex, larger vertex, corner).
// Counting sort on the smaller vertex, then small per-vertex sorts.
std::vector<uint32_t> group_edges(const std::vector<uint32_t>& idx, size_t n) {
  auto lo = [&](uint32_t c) { return std::min(idx[c], idx[next_corner(c)]); };
  auto hi = [&](uint32_t c) { return std::max(idx[c], idx[next_corner(c)]); };
  std::vector<uint32_t> offsets(n + 1, 0), uses(idx.size());
  for (uint32_t c = 0; c < idx.size(); ++c) ++offsets[lo(c) + 1];
  for (size_t v = 0; v < n; ++v) offsets[v + 1] += offsets[v];
  {
    std::vector<uint32_t> fill(offsets.begin(), offsets.end() - 1);
    for (uint32_t c = 0; c < idx.size(); ++c) uses[fill[lo(c)]++] = c;
  }
  for (size_t v = 0; v < n; ++v)
    std::sort(uses.begin() + offsets[v], uses.begin() + offsets[v + 1],
              [&](uint32_t a, uint32_t b) { return hi(a) < hi(b) || (hi(a) == hi(b) && a < b); });
  return uses;
}

// Calls visit(begin, end) for each run of corner-edges on one undirected edge.
template <class Visit>
void for_each_edge(const std::vector<uint32_t>& idx, const std::vector<uint32_t>& uses, Visit&& visit) {
  auto same_edge = [&](uint32_t a, uint32_t b) {
    return std::minmax(idx[a], idx[next_corner(a)]) == std::minmax(idx[b], idx[next_corner(b)]);
  };
  for (size_t i = 0; i < uses.size();) {
    size_t j = i + 1;
    while (j < uses.size() && same_edge(uses[i], uses[j])) ++j;
    visit(i, j);
    i = j;
  }
}

// mate[c] = the corner-edge glued to corner-edge c, or kNone. An edge with more than two faces keeps
// its first face and the first later face running the other way (else the second face); the rest
// are cut off it.
std::vector<uint32_t> glue_edges(const std::vector<uint32_t>& idx, const std::vector<uint32_t>& uses,
                                 CleanReport& report) {
  std::vector<uint32_t> mate(idx.size(), kNone);
  for_each_edge(idx, uses, [&](size_t begin, size_t end) {
    if (end - begin < 2) return;
    const uint32_t a = uses[begin];
    uint32_t b = uses[begin + 1];
    for (size_t k = begin + 1; k < end; ++k)
      if (idx[uses[k]] != idx[a]) {
        b = uses[k];
        break;
      }
    mate[a] = b;
    mate[b] = a;
    if (end - begin > 2) ++report.nonmanifold_edges;
  });
  return mate;
}

void cut(std::vector<uint32_t>& mate, uint32_t c, CleanReport& report) {
  if (mate[c] == kNone) return;
  mate[mate[c]] = kNone;
  mate[c] = kNone;
  ++report.nonmanifold_edges;
}

// Breadth-first over glued edges from the lowest face of each component; a face is flipped when its
// glued neighbour runs the shared edge the same way. A glue contradicting earlier choices means the
// component is not orientable there: it is cut. Each component then keeps the orientation most of
// its faces had. Returns flip[f] (0 or 1).
std::vector<uint8_t> orient(const std::vector<uint32_t>& idx, std::vector<uint32_t>& mate, CleanReport& report) {
  const uint32_t m = uint32_t(idx.size() / 3);
  constexpr uint8_t kUnvisited = 2;
  std::vector<uint8_t> flip(m, kUnvisited);
  std::vector<uint32_t> queue;
  for (uint32_t seed = 0; seed < m; ++seed) {
    if (flip[seed] != kUnvisited) continue;
    queue.assign(1, seed);
    flip[seed] = 0;
    size_t flipped = 0;
    for (size_t q = 0; q < queue.size(); ++q) {
      const uint32_t f = queue[q];
      for (uint32_t c = 3 * f; c < 3 * f + 3; ++c) {
        const uint32_t o = mate[c];
        if (o == kNone) continue;
        const uint32_t g = o / 3;
        const uint8_t wanted = flip[f] ^ uint8_t(idx[o] == idx[c]);  // same start vertex: same direction
        if (flip[g] == kUnvisited) {
          flip[g] = wanted;
          flipped += wanted;
          queue.push_back(g);
        } else if (flip[g] != wanted) {
          cut(mate, c, report);
        }
      }
    }
    if (2 * flipped > queue.size())
      for (uint32_t f : queue) flip[f] ^= 1;
  }
  return flip;
}

struct UnionFind {
  std::vector<uint32_t> parent;
  explicit UnionFind(size_t size) : parent(size) {
    for (size_t i = 0; i < size; ++i) parent[i] = uint32_t(i);
  }
  uint32_t find(uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void join(uint32_t a, uint32_t b) {
    a = find(a), b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

// The fans: corners at one vertex joined across glued edges. Each corner has two edges at its vertex and
// each edge at most one mate, so a fan is a chain or a cycle of consistently oriented faces. The first fan
// of a vertex (in corner order) keeps the vertex; every other fan gets a new vertex numbered from n on.
// Returns the vertex of every corner; `source` gets the original vertex of every new one.
std::vector<uint32_t> assign_fans(const std::vector<uint32_t>& idx, const std::vector<uint32_t>& mate, size_t n,
                                  std::vector<uint32_t>& source) {
  const uint32_t corners = uint32_t(idx.size());
  UnionFind fans(corners);
  for (uint32_t c = 0; c < corners; ++c) {
    const uint32_t o = mate[c];
    if (o == kNone || o < c) continue;
    const bool same_direction = idx[o] == idx[c];
    fans.join(c, same_direction ? o : next_corner(o));
    fans.join(next_corner(c), same_direction ? next_corner(o) : o);
  }
  std::vector<uint32_t> vertex(corners);
  for (uint32_t c = 0; c < corners; ++c) vertex[c] = fans.find(c);
  std::vector<uint32_t>& vertex_of_root = fans.parent;  // every root is known now: reuse the storage
  std::fill(vertex_of_root.begin(), vertex_of_root.end(), kNone);
  std::vector<uint8_t> claimed(n, 0);
  source.clear();
  for (uint32_t c = 0; c < corners; ++c) {
    uint32_t& target = vertex_of_root[vertex[c]];
    if (target == kNone) {
      const uint32_t v = idx[c];
      if (!claimed[v]) {
        claimed[v] = 1;
        target = v;
      } else {
        target = uint32_t(n + source.size());
        source.push_back(v);
      }
    }
    vertex[c] = target;
  }
  return vertex;
}

// Two faces on one edge that were not glued can still end up with the same copies of both end vertices,
// when each end's fan runs around from one face to the other (say a cut face whose other edges are glued
// into a closed fan). For each such pair, cut the other glued edge of the unglued face at the smaller
// vertex: that corner is then a fan of its own and gets its own copy. Cutting only splits fans, so no new
// pair appears. Returns whether anything was cut.
bool separate_touching_faces(const std::vector<uint32_t>& idx, const std::vector<uint32_t>& uses,
                             std::vector<uint32_t>& mate, const std::vector<uint32_t>& vertex, CleanReport& report) {
  std::vector<std::array<uint32_t, 3>> ends;  // (copy of smaller end, copy of larger end, corner-edge)
  std::vector<uint32_t> to_cut;
  for_each_edge(idx, uses, [&](size_t begin, size_t end) {
    if (end - begin < 2 || (end - begin == 2 && mate[uses[begin]] == uses[begin + 1])) return;
    ends.clear();
    for (size_t k = begin; k < end; ++k) {
      const uint32_t c = uses[k], d = next_corner(c);
      ends.push_back(idx[c] < idx[d] ? std::array{vertex[c], vertex[d], c} : std::array{vertex[d], vertex[c], c});
    }
    std::sort(ends.begin(), ends.end());
    for (size_t k = 1; k < ends.size(); ++k) {
      const uint32_t a = ends[k - 1][2], b = ends[k][2];
      if (ends[k - 1][0] != ends[k][0] || ends[k - 1][1] != ends[k][1] || mate[a] == b) continue;
      const uint32_t loose = mate[b] == kNone ? b : a;  // at most one of them is glued (to a third face)
      const bool starts_low = idx[loose] < idx[next_corner(loose)];
      to_cut.push_back(starts_low ? prev_corner(loose) : next_corner(loose));  // its other edge at that vertex
    }
  });
  for (uint32_t c : to_cut) cut(mate, c, report);
  return !to_cut.empty();
}

void repair_manifold(Mesh& mesh, CleanReport& report) {
  const size_t n = mesh.vertex_count();
  const std::vector<uint32_t> uses = group_edges(mesh.indices, n);
  std::vector<uint32_t> mate = glue_edges(mesh.indices, uses, report);
  const std::vector<uint8_t> flip = orient(mesh.indices, mate, report);
  std::vector<uint32_t> source;
  std::vector<uint32_t> vertex = assign_fans(mesh.indices, mate, n, source);
  if (separate_touching_faces(mesh.indices, uses, mate, vertex, report))
    vertex = assign_fans(mesh.indices, mate, n, source);

  std::vector<uint8_t> split(n, 0);
  for (uint32_t v : source)
    if (!split[v]) {
      split[v] = 1;
      ++report.nonmanifold_vertices;
    }
  report.split_vertex_copies = source.size();
  mesh.indices = std::move(vertex);
  for (size_t f = 0; f < flip.size(); ++f)
    if (flip[f]) {
      std::swap(mesh.indices[3 * f + 1], mesh.indices[3 * f + 2]);
      ++report.flipped_faces;
    }
  if (source.empty()) return;
  std::vector<uint32_t> all(n + source.size());  // old vertices stay where they are, copies follow
  for (uint32_t v = 0; v < n; ++v) all[v] = v;
  std::copy(source.begin(), source.end(), all.begin() + n);
  gather_vertices(mesh, all);
}

}  // namespace

CleanReport clean_mesh(Mesh& mesh) {
  check_input(mesh);
  CleanReport report;
  weld(mesh, report);
  drop_bad_faces(mesh, report);
  drop_unreferenced(mesh, report);
  if (mesh.face_count() == 0) fail("", "mesh: no faces left after dropping degenerate faces");
  // Most scans are oriented manifolds already, and checking is cheaper than repairing.
  if (!is_oriented_manifold(mesh)) {
    repair_manifold(mesh, report);
    std::string why;
    if (!is_oriented_manifold(mesh, &why)) fail("", "mesh: internal error, cleaning left " + why);
  }
  const OutwardReport outward = orient_closed_components_outward(mesh);
  report.inside_out_components = outward.components;
  report.inside_out_faces = outward.faces;
  return report;
}

}  // namespace pms
