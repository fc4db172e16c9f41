// Entry point of the build layer: simplify (balanced or greedy), then pack the forest breadth-first
// (kim-lee-kobbelt §6.1: parent index < child index, so per-session active tags can be a window).
#include "builder/build.h"

#include <algorithm>
#include <chrono>

#include "builder/bounds.h"
#include "builder/nested_refine_info.h"
#include "builder/simplify.h"
#include "common/error.h"
#include "spm/hierarchy.h"
#include "spm/pms_file.h"
#include "spm/vertex_id.h"

namespace pms {
namespace {

// Breadth-first order of the temporary forest: roots in base-vertex order, then level by level (v_t before
// v_u). kim-lee-kobbelt §6.1 leaves the order within a level free; ours puts the children of the largest
// deviations first. Views want those splits first and from farther away, so their children are the ones
// usually active: a session's deepest active node sits early in its level and its tag window ends sooner
// (along E3's orbit the window shrank by a quarter on bunny and dragon).
std::vector<uint32_t> breadth_first(const CollapseForest& forest) {
  std::vector<uint32_t> order(forest.root_node);
  order.reserve(forest.node_count());
  // Half-float bits of non-negative values order as the values.
  const auto deviation = [&](uint32_t node) { return std::max(forest.info[node].mu, forest.info[node].delta); };
  // A level's parents as one word each, the larger deviation first, then the level's order (a stable
  // sort's), and the parent's place in the level: sorting plain integers reads no node while it compares.
  std::vector<uint64_t> parents;
  for (size_t level_begin = 0; level_begin < order.size();) {
    const size_t level_end = order.size();
    parents.clear();
    for (size_t i = level_begin; i < level_end; ++i)
      if (order[i] >= forest.leaf_count)
        parents.push_back(uint64_t(UINT16_MAX - deviation(order[i])) << 32 | (i - level_begin));
    std::sort(parents.begin(), parents.end());
    for (const uint64_t parent : parents) {
      const uint32_t k = order[level_begin + uint32_t(parent)] - forest.leaf_count;
      order.push_back(forest.child_t[k]);
      order.push_back(forest.child_u[k]);
    }
    level_begin = level_end;
  }
  return order;
}

Hierarchy pack(const Mesh& mesh, const CollapseForest& forest, float scale) {
  const std::vector<uint32_t> order = breadth_first(forest);
  const uint32_t n = forest.node_count();
  if (order.size() != n) fail("", "internal error: hierarchy is not a forest over every vertex");
  std::vector<uint32_t> index_of(n);
  for (uint32_t i = 0; i < n; ++i) index_of[order[i]] = i;

  Hierarchy h;
  h.root_count = uint32_t(forest.root_node.size());
  h.base_faces = forest.base_faces;  // root order == BFS prefix
  h.parent.assign(n, kNone);
  h.first_child.assign(n, kNone);
  h.position.resize(3 * size_t(n));
  h.cut_left.assign(n, kNone);
  h.cut_right.assign(n, kNone);
  h.refine.resize(n);
  h.leaf_vertex.assign(n, kNone);
  if (mesh.has_normals()) h.normals.resize(3 * size_t(n));
  if (mesh.has_colors()) h.colors.resize(4 * size_t(n));
  for (uint32_t i = 0; i < n; ++i) {
    const uint32_t node = order[i];
    const uint32_t leaf = forest.survivor_leaf[node];
    std::copy_n(&mesh.positions[3 * size_t(leaf)], 3, &h.position[3 * size_t(i)]);
    if (mesh.has_normals()) std::copy_n(&mesh.normals[3 * size_t(leaf)], 3, &h.normals[3 * size_t(i)]);
    if (mesh.has_colors()) std::copy_n(&mesh.colors[4 * size_t(leaf)], 4, &h.colors[4 * size_t(i)]);
    h.refine[i] = forest.info[node];
    if (node < forest.leaf_count) {
      h.leaf_vertex[i] = node;
      continue;
    }
    const uint32_t k = node - forest.leaf_count;
    const uint32_t child = index_of[forest.child_t[k]];
    h.first_child[i] = child;
    h.parent[child] = h.parent[child + 1] = i;
    if (forest.cut_l[k] != UINT32_MAX) h.cut_left[i] = index_of[forest.cut_l[k]];
    if (forest.cut_r[k] != UINT32_MAX) h.cut_right[i] = index_of[forest.cut_r[k]];
  }
  // PM order = reverse collapse order.
  h.split_order.reserve(forest.child_t.size());
  for (size_t k = forest.child_t.size(); k-- > 0;) h.split_order.push_back(index_of[forest.leaf_count + uint32_t(k)]);

  const Bounds bounds = bounds_of(mesh.positions);
  std::copy_n(bounds.lo, 3, h.bbox_min);
  std::copy_n(bounds.hi, 3, h.bbox_max);
  h.scale = scale;
  h.compute_ids();
  return h;
}

}  // namespace

std::string options_text(const BuildOptions& options) {
  std::string text = options.greedy ? "greedy" : "balanced";
  text += " base_vertices=" + std::to_string(options.base_vertices);
  text += options.deviation == Deviation::bound ? " deviation=bound" : " deviation=estimate";
  if (!options.nested_info) text += " info=unnested";
  return text;
}

BuildResult build_progressive_mesh(const Mesh& mesh, const BuildOptions& options) {
  if (mesh.face_count() == 0) fail("", "mesh has no faces");
  const auto start = std::chrono::steady_clock::now();
  CollapseForest forest = options.greedy ? simplify_greedy(mesh, options) : simplify_balanced(mesh, options);
  report(options.progress, "pack", 0);
  BuildResult result;
  if (options.nested_info) nest_refine_info(forest);
  result.hierarchy = pack(mesh, forest, bounds_of(mesh.positions).diagonal());
  report(options.progress, "pack", 1);

  const Hierarchy& h = result.hierarchy;
  BuildStats& s = result.stats;
  s.options = options_text(options);
  s.input_vertices = mesh.vertex_count();
  s.input_faces = mesh.face_count();
  s.base_vertices = h.root_count;
  s.base_faces = h.base_faces.size() / 3;
  s.vsplits = h.split_order.size();
  s.tree_id_bits = tree_id_bits(h.root_count);
  s.max_depth = max_depth(h);
  s.node_id_bits = s.max_depth;
  s.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace pms
