// Gueziec, Taubin, Horn, Lazarus 1999, "From edge collapses to a progressive multilevel representation":
// levels from a collapse sequence (Fig. 4), then vertices and triangles sorted by decreasing level with the
// representatives that triangles need (Fig. 5), and consecutive levels merged to a requested count.
#include "multilevel/build.h"

#include <algorithm>
#include <numeric>
#include <queue>

#include "common/error.h"

namespace pms {
namespace {

constexpr uint32_t kNoRep = MultilevelMesh::kNoRepresentative;

std::string str(uint64_t v) { return std::to_string(v); }

bool degenerate(const uint32_t* c) { return c[0] == c[1] || c[1] == c[2] || c[2] == c[0]; }

// The collapse sequence played on the mesh: current corners and the live triangles around each vertex.
struct CollapsePlayback {
  std::vector<uint32_t> corners;             // current vertex of each corner
  std::vector<std::vector<uint32_t>> faces;  // per live vertex: triangles that were live when added
  std::vector<uint8_t> removed_vertex, removed_face;
  std::vector<uint32_t> running_level;    // 1-based, as in the paper
  std::vector<uint32_t> last_touched_by;  // per vertex: the blue vertex of the last collapse that set its level
  std::vector<uint32_t> listed_for;       // per blue vertex: 1 + the collapse whose touchers last listed it

  explicit CollapsePlayback(const Mesh& mesh)
      : corners(mesh.indices),
        faces(mesh.vertex_count()),
        removed_vertex(mesh.vertex_count()),
        removed_face(mesh.face_count()),
        running_level(mesh.vertex_count()),
        last_touched_by(mesh.vertex_count(), kNoRep),
        listed_for(mesh.vertex_count(), 0) {
    for (uint32_t t = 0; t < mesh.face_count(); ++t) {
      if (degenerate(&corners[3 * size_t(t)])) {
        removed_face[t] = 1;  // never part of a surface: level 0
        continue;
      }
      for (int k = 0; k < 3; ++k) faces[corners[3 * size_t(t) + k]].push_back(t);
    }
  }

  // The highest running level over the star of edge (a, b), its endpoints and their neighbours; appends
  // the collapses that last touched them to `touchers`, once each (`collapse` is the sequence index).
  uint32_t star_level(uint32_t a, uint32_t b, uint32_t collapse, std::vector<uint32_t>& touchers) {
    uint32_t level = 0;
    auto visit = [&](uint32_t v) {
      level = std::max(level, running_level[v]);
      const uint32_t u = last_touched_by[v];
      if (u != kNoRep && listed_for[u] != collapse + 1) {
        listed_for[u] = collapse + 1;
        touchers.push_back(u);
      }
    };
    visit(a);
    visit(b);
    for (uint32_t v : {a, b})
      for (uint32_t t : faces[v]) {
        if (removed_face[t]) continue;
        for (int k = 0; k < 3; ++k) visit(corners[3 * size_t(t) + k]);
      }
    return level;
  }
};

void check_collapse(const CollapsePlayback& p, const EdgeCollapse& c, size_t i) {
  const size_t n = p.removed_vertex.size();
  if (c.removed >= n || c.survivor >= n) fail("", "collapse " + str(i) + " names a vertex beyond the mesh's " + str(n));
  if (c.removed == c.survivor) fail("", "collapse " + str(i) + " collapses vertex " + str(c.removed) + " onto itself");
  if (p.removed_vertex[c.removed] || p.removed_vertex[c.survivor])
    fail("", "collapse " + str(i) + " names a vertex an earlier collapse removed");
}

// Indices sorted by decreasing level, ties in input order.
std::vector<uint32_t> by_decreasing_level(const std::vector<uint32_t>& level) {
  std::vector<uint32_t> order(level.size());
  std::iota(order.begin(), order.end(), 0u);
  std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return level[a] > level[b]; });
  return order;
}

// Vertices by decreasing level; within a level, numbered so that the replay from the last vertex makes
// each collapse after those `earlier` names and after its children's: Kahn's algorithm taking the highest
// input index first, the first taken numbered last (so independent collapses keep input order).
std::vector<uint32_t> replay_numbering(const CollapseLevels& levels) {
  const std::vector<uint32_t>& level = levels.vertex_level;
  const uint32_t n = uint32_t(level.size());
  std::vector<uint32_t> order = by_decreasing_level(level);
  // Edges "u's collapse before a's" within one level, as successor rows.
  std::vector<uint32_t> offsets(size_t(n) + 1, 0), successors, waiting(n, 0);
  auto for_each_edge = [&](auto&& edge) {
    for (size_t i = 0; i < levels.collapse_removed.size(); ++i) {
      const uint32_t a = levels.collapse_removed[i];
      for (uint32_t k = levels.earlier_offsets[i]; k < levels.earlier_offsets[i + 1]; ++k)
        if (level[levels.earlier[k]] == level[a]) edge(levels.earlier[k], a);
    }
    for (uint32_t a = 0; a < n; ++a)
      if (levels.parent[a] != kNoRep && level[levels.parent[a]] == level[a]) edge(a, levels.parent[a]);
  };
  for_each_edge([&](uint32_t u, uint32_t a) { ++offsets[u + 1], ++waiting[a]; });
  if (std::all_of(waiting.begin(), waiting.end(), [](uint32_t w) { return w == 0; })) return order;  // unmerged
  for (uint32_t v = 0; v < n; ++v) offsets[v + 1] += offsets[v];
  successors.resize(offsets[n]);
  std::vector<uint32_t> fill(offsets.begin(), offsets.end() - 1);
  for_each_edge([&](uint32_t u, uint32_t a) { successors[fill[u]++] = a; });

  std::vector<uint32_t> numbered(n);
  std::priority_queue<uint32_t> ready;
  for (uint32_t begin = 0; begin < n;) {
    uint32_t end = begin;
    while (end < n && level[order[end]] == level[order[begin]]) ++end;
    for (uint32_t i = begin; i < end; ++i)
      if (waiting[order[i]] == 0) ready.push(order[i]);
    uint32_t next = end;
    while (!ready.empty()) {
      const uint32_t v = ready.top();
      ready.pop();
      numbered[--next] = v;
      for (uint32_t k = offsets[v]; k < offsets[v + 1]; ++k)
        if (--waiting[successors[k]] == 0) ready.push(successors[k]);
    }
    // The edges follow the collapse sequence, so they cannot close a cycle.
    if (next != begin) fail("", "the collapses' order has a cycle");
    begin = end;
  }
  return numbered;
}

std::vector<uint32_t> counts_per_level(const std::vector<uint32_t>& level, uint32_t level_count) {
  std::vector<uint32_t> count(level_count + 1, 0);
  for (uint32_t l : level) ++count[l];
  for (uint32_t l = level_count; l-- > 0;) count[l] += count[l + 1];  // levels >= l
  count.pop_back();
  return count;
}

}  // namespace

std::vector<EdgeCollapse> collapses_of(const Hierarchy& hierarchy) { return collapses_of(model_of(hierarchy)); }

std::vector<EdgeCollapse> collapses_of(const ModelData& h) {
  const size_t n = h.node_count();
  std::vector<uint32_t> leaf(n, kNone);
  for (size_t i = n; i-- > 0;)  // children come after their parent
    leaf[i] = h.is_leaf(uint32_t(i)) ? h.leaf_vertex[i] : leaf[h.first_child[i] + 1];
  std::vector<EdgeCollapse> collapses;
  collapses.reserve(h.split_order.size());
  for (size_t i = h.split_order.size(); i-- > 0;) {
    const uint32_t c = h.first_child[h.split_order[i]];
    collapses.push_back({leaf[c], leaf[c + 1]});
  }
  return collapses;
}

CollapseLevels assign_levels(const Mesh& mesh, std::span<const EdgeCollapse> collapses) {
  CollapsePlayback p(mesh);
  CollapseLevels out;
  out.vertex_level.assign(mesh.vertex_count(), 0);
  out.triangle_level.assign(mesh.face_count(), 0);
  out.parent.assign(mesh.vertex_count(), kNoRep);
  out.collapse_removed.reserve(collapses.size());
  out.earlier_offsets.reserve(collapses.size() + 1);
  out.earlier_offsets.push_back(0);
  uint32_t top = 0;
  std::vector<uint32_t> touchers;
  for (size_t i = 0; i < collapses.size(); ++i) {
    const auto [a, b] = collapses[i];
    check_collapse(p, collapses[i], i);
    touchers.clear();
    const uint32_t level = p.star_level(a, b, uint32_t(i), touchers) + 1;
    out.earlier.insert(out.earlier.end(), touchers.begin(), touchers.end());
    out.earlier_offsets.push_back(uint32_t(out.earlier.size()));
    out.collapse_removed.push_back(a);
    top = std::max(top, level);
    p.running_level[a] = p.running_level[b] = level;
    p.last_touched_by[a] = p.last_touched_by[b] = a;
    out.vertex_level[a] = level - 1;
    out.parent[a] = b;
    p.removed_vertex[a] = 1;
    std::vector<uint32_t>& around_b = p.faces[b];
    std::erase_if(around_b, [&](uint32_t t) { return p.removed_face[t] != 0; });
    for (uint32_t t : p.faces[a]) {
      if (p.removed_face[t]) continue;
      uint32_t* c = &p.corners[3 * size_t(t)];
      for (int k = 0; k < 3; ++k)
        if (c[k] == a) c[k] = b;
      if (degenerate(c)) {
        p.removed_face[t] = 1;
        out.triangle_level[t] = level - 1;
      } else {
        around_b.push_back(t);
      }
    }
    // Faces of b that were a's too (the ones just removed) are dropped on b's next collapse or scan.
    std::vector<uint32_t>().swap(p.faces[a]);
  }
  // Red vertices and triangles take one level above every collapse (top + 1, 1-based).
  for (uint32_t v = 0; v < mesh.vertex_count(); ++v)
    if (!p.removed_vertex[v]) out.vertex_level[v] = top;
  for (uint32_t t = 0; t < mesh.face_count(); ++t)
    if (!p.removed_face[t]) out.triangle_level[t] = top;
  out.level_count = top + 1;
  return out;
}

// Within each level, the triangles by the vertex of that level they stand on (the one a corner reaches
// in the level's LOD), each turned (its orientation kept) to start at the corner that reaches it: the
// order the compressed levels code best (multilevel/codec.h: the level's next unnamed vertex leads a
// corner's candidates). A triangle whose corners all reach coarser vertices goes after the others.
void order_level_triangles(MultilevelMesh& m) {
  std::vector<uint32_t> key, sorted;
  for (uint32_t level = 0; level < m.level_count(); ++level) {
    const uint32_t n_l = m.vertex_count[level], lo = n_l - m.level_vertices(level);
    const uint32_t t_end = m.triangle_count[level], t_begin = t_end - m.level_triangles(level);
    key.assign(t_end - t_begin, kNoRep);
    for (uint32_t t = t_begin; t < t_end; ++t) {
      uint32_t* corner = &m.triangles[3 * size_t(t)];
      for (uint32_t c = 0; c < 3; ++c) {
        uint32_t x = corner[c];
        while (x != kNoRep && x >= n_l) x = m.representative[x];
        if (x == kNoRep || x < lo) continue;
        key[t - t_begin] = x;
        std::rotate(corner, corner + c, corner + 3);
        break;
      }
    }
    std::vector<uint32_t> order(t_end - t_begin);
    std::iota(order.begin(), order.end(), 0u);
    std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return key[a] < key[b]; });
    sorted.clear();
    for (uint32_t i : order) sorted.insert(sorted.end(), &m.triangles[3 * size_t(t_begin + i)], &m.triangles[3 * size_t(t_begin + i) + 3]);
    std::copy(sorted.begin(), sorted.end(), m.triangles.begin() + 3 * long(t_begin));
  }
}

MultilevelMesh assemble_multilevel(const Mesh& mesh, const CollapseLevels& levels, MultilevelRepresentatives kind,
                                   std::vector<uint32_t>* vertex_order_out) {
  const uint32_t n = uint32_t(mesh.vertex_count()), f = uint32_t(mesh.face_count());
  const std::vector<uint32_t> vertex_order = replay_numbering(levels);
  const std::vector<uint32_t> face_order = by_decreasing_level(levels.triangle_level);
  std::vector<uint32_t> new_index(n);
  for (uint32_t i = 0; i < n; ++i) new_index[vertex_order[i]] = i;

  MultilevelMesh m;
  m.dimension = 3;
  m.vertex_count = counts_per_level(levels.vertex_level, levels.level_count);
  m.triangle_count = counts_per_level(levels.triangle_level, levels.level_count);
  m.positions.resize(size_t(n) * 3);
  if (mesh.has_normals()) m.normals.resize(size_t(n) * 3);
  if (mesh.has_colors()) m.colors.resize(size_t(n) * 4);
  if (mesh.has_texcoords()) m.texcoords.resize(size_t(n) * 2);
  for (uint32_t i = 0; i < n; ++i) {
    const uint32_t v = vertex_order[i];
    std::copy_n(&mesh.positions[3 * size_t(v)], 3, &m.positions[3 * size_t(i)]);
    if (mesh.has_normals()) std::copy_n(&mesh.normals[3 * size_t(v)], 3, &m.normals[3 * size_t(i)]);
    if (mesh.has_colors()) std::copy_n(&mesh.colors[4 * size_t(v)], 4, &m.colors[4 * size_t(i)]);
    if (mesh.has_texcoords()) std::copy_n(&mesh.texcoords[2 * size_t(v)], 2, &m.texcoords[2 * size_t(i)]);
  }
  m.triangles.resize(size_t(f) * 3);
  for (uint32_t i = 0; i < f; ++i)
    for (int k = 0; k < 3; ++k) m.triangles[3 * size_t(i) + k] = new_index[mesh.indices[3 * size_t(face_order[i]) + k]];

  // needed[x] = 1 + the highest triangle level k whose LOD misses x, or for a geomorph (k below the top)
  // whose LOD k + 1 does: a chain already marked that high stops the walk, so every vertex is visited O(1)
  // times per level.
  const bool morph = kind == MultilevelRepresentatives::geomorph;
  std::vector<uint32_t> needed(n, 0);
  for (uint32_t t = 0; t < f; ++t) {
    const uint32_t k = levels.triangle_level[t];
    const uint32_t end = morph && k + 1 < levels.level_count ? k + 1 : k;  // chains run below level `end`
    for (int c = 0; c < 3; ++c)
      for (uint32_t x = mesh.indices[3 * size_t(t) + c]; x != kNoRep && levels.vertex_level[x] < end && needed[x] <= k;
           x = levels.parent[x])
        needed[x] = k + 1;
  }
  m.representative.assign(n, kNoRep);
  for (uint32_t x = 0; x < n; ++x)
    if (needed[x]) m.representative[new_index[x]] = new_index[levels.parent[x]];
  if (vertex_order_out) *vertex_order_out = vertex_order;
  return m;
}

std::vector<uint32_t> merge_level_map(uint32_t from, uint32_t to) {
  std::vector<uint32_t> map(from);
  for (uint32_t k = 0; k < from; ++k) map[k] = to == 0 || to >= from ? k : uint32_t(uint64_t(k) * to / from);
  return map;
}

void merge_levels(CollapseLevels& levels, uint32_t level_count) {
  if (level_count == 0 || level_count >= levels.level_count) return;
  const std::vector<uint32_t> map = merge_level_map(levels.level_count, level_count);
  for (uint32_t& l : levels.vertex_level) l = map[l];
  for (uint32_t& l : levels.triangle_level) l = map[l];
  levels.level_count = level_count;
}

MultilevelMesh build_multilevel(const Mesh& mesh, std::span<const EdgeCollapse> collapses, uint32_t level_count,
                                MultilevelRepresentatives kind) {
  CollapseLevels levels = assign_levels(mesh, collapses);
  merge_levels(levels, level_count);
  MultilevelMesh m = assemble_multilevel(mesh, levels, kind);
  order_level_triangles(m);
  return m;
}

}  // namespace pms
