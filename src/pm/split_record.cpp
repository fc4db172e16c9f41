#include "pm/split_record.h"

#include <algorithm>
#include <string>
#include <utility>

#include "common/error.h"
#include "pm/hierarchy.h"
#include "pm/vertex_id.h"

namespace pms {

SplitRecord split_record(const ModelView& view, uint32_t node) {
  check_node_arrays(view);
  const size_t n = view.node_count();
  if (node >= n || view.is_leaf(node)) fail("model", "node " + std::to_string(node) + " is not an internal node");
  const uint32_t t = view.first_child[node];
  if (t + size_t(1) >= n) fail("model", "node " + std::to_string(node) + ": child index out of range");
  SplitRecord split;
  split.vs = view.id(node);
  for (auto [cut, index] : {std::pair{&split.cut_l, view.cut_left[node]}, std::pair{&split.cut_r, view.cut_right[node]}}) {
    if (index == kNone) continue;
    if (index >= n) fail("model", "node " + std::to_string(node) + ": cut vertex index out of range");
    *cut = view.id(index);
  }
  std::copy_n(&view.position[3 * size_t(t)], 3, split.position_t);
  split.info_t = view.refine[t];
  split.info_u = view.refine[t + 1];
  split.has_normal = !view.normals.empty();
  if (split.has_normal) std::copy_n(&view.normals[3 * size_t(t)], 3, split.normal_t);
  split.has_color = !view.colors.empty();
  if (split.has_color) std::copy_n(&view.colors[4 * size_t(t)], 4, split.color_t);
  return split;
}

}  // namespace pms
