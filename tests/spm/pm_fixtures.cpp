#include "pm_fixtures.h"

#include <algorithm>
#include <cmath>

#include "spm/hierarchy.h"
#include "spm/refine_info.h"
#include "spm/vertex_id.h"

namespace pms::test {
namespace {

RefineInfo refine_for_depth(int depth, float scale) {
  RefineBounds b;
  b.radius = 0.5f * scale / float(1 + depth);
  b.mu = b.radius * 0.1f;
  b.delta = b.radius * 0.05f;
  b.cone_angle = 0.2f + 0.1f * float(depth % 5);
  return quantize_refine(b, scale);
}

// bbox and scale (its diagonal) from the positions, as the builder does.
void set_bounds(Hierarchy& h) {
  std::fill_n(h.bbox_min, 3, INFINITY);
  std::fill_n(h.bbox_max, 3, -INFINITY);
  for (size_t i = 0; i < h.position.size(); ++i) {
    h.bbox_min[i % 3] = std::min(h.bbox_min[i % 3], h.position[i]);
    h.bbox_max[i % 3] = std::max(h.bbox_max[i % 3], h.position[i]);
  }
  float squared = 0;
  for (int k = 0; k < 3; ++k) squared += (h.bbox_max[k] - h.bbox_min[k]) * (h.bbox_max[k] - h.bbox_min[k]);
  h.scale = std::sqrt(squared);
}

}  // namespace

Hierarchy make_small_hierarchy(bool attributes) {
  Hierarchy h;
  h.root_count = 3;
  h.base_faces = {0, 1, 2};
  //             0      1      2      3      4  5      6      7      8
  h.parent = {kNone, kNone, kNone, 0, 0, 1, 1, 4, 4};
  h.first_child = {3, 5, kNone, kNone, 7, kNone, kNone, kNone, kNone};
  // v_u (second child) keeps its parent's position; v_t brings a new one.
  h.position = {0, 0, 0, 1, 0, 0, 0, 1, 0, -0.5f, 0, 0.25f, 0, 0, 0, 1, -0.5f, 0, 1, 0, 0, 0.25f, 0.25f, 0.5f, 0, 0, 0};
  h.cut_left = {2, 2, kNone, kNone, 3, kNone, kNone, kNone, kNone};
  h.cut_right = {5, kNone, kNone, kNone, 2, kNone, kNone, kNone, kNone};
  h.leaf_vertex = {kNone, kNone, 0, 1, kNone, 2, 3, 4, 5};
  h.split_order = {1, 0, 4};
  set_bounds(h);
  const int depth[9] = {0, 0, 0, 1, 1, 1, 1, 2, 2};
  for (int d : depth) h.refine.push_back(refine_for_depth(d, h.scale));
  if (attributes) {
    for (int i = 0; i < 9; ++i) {
      const float n[3] = {0, float(i % 2) * 0.6f, i % 2 ? 0.8f : 1.0f};
      h.normals.insert(h.normals.end(), n, n + 3);
      const uint8_t c[4] = {uint8_t(20 * i), uint8_t(255 - 20 * i), 7, 255};
      h.colors.insert(h.colors.end(), c, c + 4);
    }
  }
  h.compute_ids();
  return h;
}

Hierarchy make_forest(uint32_t roots, const SplitRule& split) {
  struct Node {
    uint32_t tree;
    int depth;
    bool leftmost;
  };
  Hierarchy h;
  h.root_count = roots;
  std::vector<Node> nodes;
  for (uint32_t r = 0; r < roots; ++r) {
    nodes.push_back({r, 0, true});
    h.parent.push_back(kNone);
    h.first_child.push_back(kNone);
    const float p[3] = {float(r), float(r % 3), 0};
    h.position.insert(h.position.end(), p, p + 3);
  }
  // Appending children while scanning keeps the array breadth-first by depth.
  for (uint32_t i = 0; i < nodes.size(); ++i) {
    const Node n = nodes[i];
    if (!split(n.tree, n.depth, n.leftmost)) continue;
    h.first_child[i] = uint32_t(nodes.size());
    nodes.push_back({n.tree, n.depth + 1, n.leftmost});
    nodes.push_back({n.tree, n.depth + 1, false});
    const float* p = &h.position[3 * size_t(i)];
    const float t[3] = {p[0] + 0.01f * float(i % 7), p[1] + 0.01f * float(i % 11), p[2] + 0.01f * float(i % 13)};
    const float u[3] = {p[0], p[1], p[2]};
    h.position.insert(h.position.end(), t, t + 3);
    h.position.insert(h.position.end(), u, u + 3);
    for (int k = 0; k < 2; ++k) {
      h.parent.push_back(i);
      h.first_child.push_back(kNone);
    }
  }
  const size_t count = nodes.size();
  std::vector<uint32_t> first_leaf(roots);  // of each tree, down the first-child path
  for (uint32_t r = 0; r < roots; ++r) {
    uint32_t n = r;
    while (h.first_child[n] != kNone) n = h.first_child[n];
    first_leaf[r] = n;
  }
  h.cut_left.assign(count, kNone);
  h.cut_right.assign(count, kNone);
  h.leaf_vertex.assign(count, kNone);
  set_bounds(h);
  uint32_t leaves = 0;
  for (uint32_t i = 0; i < count; ++i) {
    h.refine.push_back(refine_for_depth(nodes[i].depth, h.scale));
    if (h.first_child[i] == kNone) {
      h.leaf_vertex[i] = leaves++;
      continue;
    }
    h.split_order.push_back(i);  // breadth-first: parents before children
    h.cut_left[i] = first_leaf[(nodes[i].tree + 1) % roots];
    if (i % 2 == 0) h.cut_right[i] = h.cut_left[i];  // odd nodes: one-sided (boundary) splits
  }
  return h;
}

}  // namespace pms::test
