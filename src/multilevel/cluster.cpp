// Gueziec, Taubin, Horn, Lazarus 1999, "From vertex clusterings" (Fig. 12-13): each clustering is one level;
// the preferred ancestor of a cluster is its nearest, the other ancestors and the triangles that degenerate
// take the clustering's level. Representatives then come from assemble_multilevel, which keeps only those
// some triangle needs.
#include "multilevel/cluster.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "common/error.h"

namespace pms {
namespace {

constexpr uint32_t kNoRep = MultilevelMesh::kNoRepresentative;

std::string str(uint64_t v) { return std::to_string(v); }

float distance2(const float* a, const float* b) {
  float d = 0;
  for (int k = 0; k < 3; ++k) d += (a[k] - b[k]) * (a[k] - b[k]);
  return d;
}

// Per cluster, its preferred ancestor among the live vertices.
std::vector<uint32_t> preferred_ancestors(const Mesh& mesh, const VertexClustering& c,
                                          const std::vector<uint8_t>& removed, size_t index) {
  const size_t clusters = c.positions.size() / 3;
  std::vector<uint32_t> best(clusters, kNoRep);
  for (uint32_t v = 0; v < mesh.vertex_count(); ++v) {
    if (removed[v]) continue;
    const uint32_t k = c.cluster[v];
    if (k >= clusters)
      fail("", "clustering " + str(index) + " puts vertex " + str(v) + " in cluster " + str(k) +
                   ", which has no position (" + str(clusters) + " clusters)");
    const float* at = &c.positions[3 * size_t(k)];
    if (best[k] == kNoRep ||
        distance2(&mesh.positions[3 * size_t(v)], at) < distance2(&mesh.positions[3 * size_t(best[k])], at))
      best[k] = v;
  }
  return best;
}

// LOD `level`'s secondary array after `c`, the clustering it ends with: each of its vertices (multilevel
// numbering: `order` gives the input vertex of each) at its cluster's position, with the mean normal and
// colour of the input vertices it stands for (those whose parents lead to it at that level); only the
// vertices that move or change.
ChangedVertices clustered_values(const Mesh& mesh, const VertexClustering& c, const CollapseLevels& levels,
                                 const std::vector<uint32_t>& order, uint32_t level) {
  const uint32_t n = uint32_t(mesh.vertex_count());
  std::vector<uint32_t> stands_at(n, kNoRep);
  const auto stand_in = [&](uint32_t v) {
    uint32_t u = v;
    while (levels.vertex_level[u] < level && stands_at[u] == kNoRep) u = levels.parent[u];
    const uint32_t at = levels.vertex_level[u] < level ? stands_at[u] : u;
    for (uint32_t w = v; w != u; w = levels.parent[w]) stands_at[w] = at;
    return at;
  };
  std::vector<double> normal_sum(mesh.has_normals() ? 3 * size_t(n) : 0), color_sum(mesh.has_colors() ? 4 * size_t(n) : 0);
  std::vector<uint32_t> members(n, 0);
  for (uint32_t v = 0; v < n; ++v) {
    const uint32_t a = stand_in(v);
    ++members[a];
    for (size_t k = 0; k < (normal_sum.empty() ? 0 : 3); ++k) normal_sum[3 * size_t(a) + k] += mesh.normals[3 * size_t(v) + k];
    for (size_t k = 0; k < (color_sum.empty() ? 0 : 4); ++k) color_sum[4 * size_t(a) + k] += mesh.colors[4 * size_t(v) + k];
  }
  ChangedVertices out;
  for (uint32_t i = 0; i < n && levels.vertex_level[order[i]] >= level; ++i) {
    const uint32_t a = order[i];
    const float* position = &c.positions[3 * size_t(c.cluster[a])];
    float normal[3] = {0, 0, 0};
    uint8_t color[4] = {0, 0, 0, 0};
    bool differs = !std::equal(position, position + 3, &mesh.positions[3 * size_t(a)]);
    if (!normal_sum.empty()) {
      const double* s = &normal_sum[3 * size_t(a)];
      const double length = std::sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
      for (int k = 0; k < 3; ++k) normal[k] = length > 0 ? float(s[k] / length) : mesh.normals[3 * size_t(a) + k];
      differs = differs || !std::equal(normal, normal + 3, &mesh.normals[3 * size_t(a)]);
    }
    if (!color_sum.empty()) {
      for (int k = 0; k < 4; ++k) color[k] = uint8_t(std::lround(color_sum[4 * size_t(a) + k] / members[a]));
      differs = differs || !std::equal(color, color + 4, &mesh.colors[4 * size_t(a)]);
    }
    if (!differs) continue;
    out.vertex.push_back(i);
    out.positions.insert(out.positions.end(), position, position + 3);
    if (!normal_sum.empty()) out.normals.insert(out.normals.end(), normal, normal + 3);
    if (!color_sum.empty()) out.colors.insert(out.colors.end(), color, color + 4);
  }
  return out;
}

}  // namespace

CollapseLevels assign_cluster_levels(const Mesh& mesh, std::span<const VertexClustering> clusterings) {
  const uint32_t n = uint32_t(mesh.vertex_count()), f = uint32_t(mesh.face_count());
  CollapseLevels out;
  out.vertex_level.assign(n, 0);
  out.triangle_level.assign(f, 0);
  out.parent.assign(n, kNoRep);
  std::vector<uint8_t> removed_vertex(n, 0), removed_face(f, 0);
  std::vector<uint32_t> corners = mesh.indices;
  auto degenerate = [](const uint32_t* c) { return c[0] == c[1] || c[1] == c[2] || c[2] == c[0]; };
  for (uint32_t t = 0; t < f; ++t) removed_face[t] = degenerate(&corners[3 * size_t(t)]);  // level 0
  for (size_t i = 0; i < clusterings.size(); ++i) {
    const VertexClustering& c = clusterings[i];
    if (c.cluster.size() != n)
      fail("", "clustering " + str(i) + " maps " + str(c.cluster.size()) + " vertices, not " + str(n));
    const std::vector<uint32_t> best = preferred_ancestors(mesh, c, removed_vertex, i);
    const uint32_t level = uint32_t(i);
    for (uint32_t v = 0; v < n; ++v) {
      if (removed_vertex[v] || best[c.cluster[v]] == v) continue;
      removed_vertex[v] = 1;
      out.vertex_level[v] = level;
      out.parent[v] = best[c.cluster[v]];
    }
    for (uint32_t t = 0; t < f; ++t) {
      if (removed_face[t]) continue;
      uint32_t* tri = &corners[3 * size_t(t)];
      for (int k = 0; k < 3; ++k)
        if (removed_vertex[tri[k]]) tri[k] = out.parent[tri[k]];
      if (degenerate(tri)) {
        removed_face[t] = 1;
        out.triangle_level[t] = level;
      }
    }
  }
  const uint32_t top = uint32_t(clusterings.size());
  for (uint32_t v = 0; v < n; ++v)
    if (!removed_vertex[v]) out.vertex_level[v] = top;
  for (uint32_t t = 0; t < f; ++t)
    if (!removed_face[t]) out.triangle_level[t] = top;
  out.level_count = top + 1;
  return out;
}

std::vector<VertexClustering> grid_clusterings(const Mesh& mesh, std::span<const uint32_t> resolutions) {
  const size_t n = mesh.vertex_count();
  float lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
  for (size_t v = 0; v < n; ++v)
    for (int k = 0; k < 3; ++k) {
      const float p = mesh.positions[3 * v + k];
      lo[k] = v == 0 ? p : std::min(lo[k], p);
      hi[k] = v == 0 ? p : std::max(hi[k], p);
    }
  std::vector<VertexClustering> out;
  for (uint32_t cells : resolutions) {
    if (cells == 0 || cells > (1u << 20)) fail("", "a clustering grid has 1 to 2^20 cells per axis, not " + str(cells));
    VertexClustering c;
    c.cluster.resize(n);
    std::unordered_map<uint64_t, uint32_t> id_of_cell;
    std::vector<double> sum;
    std::vector<uint32_t> members;
    for (size_t v = 0; v < n; ++v) {
      uint64_t cell = 0;
      for (int k = 0; k < 3; ++k) {
        const float extent = hi[k] - lo[k];
        const float x = extent > 0 ? (mesh.positions[3 * v + k] - lo[k]) / extent * float(cells) : 0;
        cell = cell * cells + std::min<uint64_t>(cells - 1, uint64_t(std::max(0.0f, x)));
      }
      const auto [it, fresh] = id_of_cell.emplace(cell, uint32_t(members.size()));
      if (fresh) {
        members.push_back(0);
        sum.insert(sum.end(), {0.0, 0.0, 0.0});
      }
      const uint32_t id = it->second;
      c.cluster[v] = id;
      ++members[id];
      for (int k = 0; k < 3; ++k) sum[3 * size_t(id) + k] += mesh.positions[3 * v + k];
    }
    c.positions.resize(sum.size());
    for (size_t i = 0; i < sum.size(); ++i) c.positions[i] = float(sum[i] / members[i / 3]);
    out.push_back(std::move(c));
  }
  return out;
}

MultilevelMesh build_multilevel_from_clusterings(const Mesh& mesh, std::span<const VertexClustering> clusterings,
                                                 uint32_t level_count) {
  CollapseLevels levels = assign_cluster_levels(mesh, clusterings);
  const std::vector<uint32_t> merged = merge_level_map(levels.level_count, level_count);
  merge_levels(levels, level_count);
  std::vector<uint32_t> order;
  // Fig. 12: no more representatives than necessary.
  MultilevelMesh m = assemble_multilevel(mesh, levels, MultilevelRepresentatives::discrete, &order);
  m.changed.resize(m.level_count());
  for (uint32_t l = 1; l < m.level_count(); ++l) {
    // LOD l is the input after the clusterings of the levels merged below l; the last of them places it.
    const auto last = uint32_t(std::count_if(merged.begin(), merged.end(), [&](uint32_t k) { return k < l; }));
    m.changed[l] = clustered_values(mesh, clusterings[last - 1], levels, order, l);
  }
  if (m.changed_vertices() == 0) m.changed.clear();
  return m;
}

}  // namespace pms
