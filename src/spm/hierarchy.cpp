// Vertex ids over the packed hierarchy (kim-lee-kobbelt §4, §6.2): <tree-id, node-id> with a
// heap-indexed node-id, derived from the array structure rather than stored.
#include <algorithm>

#include "common/error.h"
#include "spm/hierarchy.h"
#include "spm/hierarchy_internal.h"
#include "spm/vertex_id.h"

namespace pms {
namespace detail {

void compute_ids(uint32_t root_count, std::span<const uint32_t> first_child, std::span<uint32_t> tree_id,
                 std::span<uint64_t> node_id, const std::string& where) {
  const size_t n = first_child.size();
  if (root_count > n) fail(where, std::to_string(root_count) + " roots but only " + std::to_string(n) + " nodes");
  for (uint32_t r = 0; r < root_count; ++r) {
    tree_id[r] = r;
    node_id[r] = 1;
  }
  for (size_t i = 0; i < n; ++i) {
    const uint32_t c = first_child[i];
    if (c == kNone) continue;
    if (c <= i || uint64_t(c) + 1 >= n)
      fail(where, "node " + std::to_string(i) + ": children " + std::to_string(c) + ", " +
                      std::to_string(uint64_t(c) + 1) + " are not after it inside the array");
    if (node_id[i] >> 63)
      fail(where, "node " + std::to_string(i) + ": its children would be deeper than 63 levels (node-ids are 64-bit)");
    tree_id[c] = tree_id[c + 1] = tree_id[i];
    node_id[c] = node_id[i] << 1;
    node_id[c + 1] = node_id[i] << 1 | 1;
  }
}

uint32_t find_node(uint32_t root_count, std::span<const uint32_t> first_child, VertexId id) {
  if (id.tree >= root_count || id.tree >= first_child.size() || id.node == 0) return kNone;
  uint32_t n = id.tree;
  for (int bit = id.depth() - 1; bit >= 0; --bit) {
    const uint32_t c = first_child[n];
    if (c == kNone || uint64_t(c) + 1 >= first_child.size()) return kNone;
    n = c + uint32_t((id.node >> bit) & 1);
  }
  return n;
}

}  // namespace detail

size_t Hierarchy::leaf_count() const { return size_t(std::count(first_child.begin(), first_child.end(), kNone)); }

void Hierarchy::compute_ids() {
  tree_id.assign(node_count(), 0);
  node_id.assign(node_count(), 0);
  detail::compute_ids(root_count, first_child, tree_id, node_id, "hierarchy");
}

uint32_t Hierarchy::find(VertexId id) const { return detail::find_node(root_count, first_child, id); }

uint32_t ModelData::find(VertexId id) const { return detail::find_node(root_count, first_child, id); }

// ceil(log2(n)) bits name n trees (kim-lee-kobbelt §6.2); a single tree still gets one bit so
// that every id has a tree field (and 0 or 1 roots never yield a zero-width field).
uint32_t tree_id_bits(uint64_t root_count) { return root_count <= 2 ? 1 : uint32_t(std::bit_width(root_count - 1)); }

// Depth from the parent links alone, so it does not depend on compute_ids() having run.
uint32_t max_depth(const Hierarchy& h) {
  std::vector<uint32_t> depth(h.node_count(), 0);
  uint32_t deepest = 0;
  for (size_t n = h.root_count; n < h.node_count(); ++n) {
    depth[n] = depth[h.parent[n]] + 1;  // parent index < n: its depth is already known
    deepest = std::max(deepest, depth[n]);
  }
  return deepest;
}

ModelData model_of(const Hierarchy& h) {
  ModelData v;
  v.root_count = h.root_count;
  v.base_faces = h.base_faces;
  v.parent = h.parent;
  v.first_child = h.first_child;
  v.position = h.position;
  v.cut_left = h.cut_left;
  v.cut_right = h.cut_right;
  v.refine = h.refine;
  v.leaf_vertex = h.leaf_vertex;
  v.split_order = h.split_order;
  v.normals = h.normals;
  v.colors = h.colors;
  v.tree_id = h.tree_id;
  v.node_id = h.node_id;
  v.bbox_min = h.bbox_min;
  v.bbox_max = h.bbox_max;
  v.scale = h.scale;
  return v;
}

void check_node_arrays(const ModelData& model) {
  const size_t n = model.node_count();
  if (model.root_count > n || model.first_child.size() < n || model.position.size() < 3 * n ||
      model.refine.size() < n || model.cut_left.size() < n || model.cut_right.size() < n || model.tree_id.size() < n ||
      model.node_id.size() < n || (!model.normals.empty() && model.normals.size() < 3 * n) ||
      (!model.colors.empty() && model.colors.size() < 4 * n))
    fail("model", "node arrays shorter than the node count");
}

}  // namespace pms
