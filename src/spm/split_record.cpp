#include "spm/split_record.h"

#include <algorithm>
#include <string>
#include <utility>

#include "common/error.h"
#include "spm/hierarchy.h"
#include "spm/vertex_id.h"

namespace pms {

SplitRecord split_record(const ModelData& model, uint32_t node) {
  check_node_arrays(model);
  const size_t n = model.node_count();
  if (node >= n || model.is_leaf(node)) fail("model", "node " + std::to_string(node) + " is not an internal node");
  const uint32_t t = model.first_child[node];
  if (t + size_t(1) >= n) fail("model", "node " + std::to_string(node) + ": child index out of range");
  SplitRecord split;
  split.vs = model.id(node);
  for (auto [cut, index] :
       {std::pair{&split.cut_l, model.cut_left[node]}, std::pair{&split.cut_r, model.cut_right[node]}}) {
    if (index == kNone) continue;
    if (index >= n) fail("model", "node " + std::to_string(node) + ": cut vertex index out of range");
    *cut = model.id(index);
  }
  std::copy_n(&model.position[3 * size_t(t)], 3, split.position_t);
  split.info_t = model.refine[t];
  split.info_u = model.refine[t + 1];
  split.has_normal = !model.normals.empty();
  if (split.has_normal) std::copy_n(&model.normals[3 * size_t(t)], 3, split.normal_t);
  split.has_color = !model.colors.empty();
  if (split.has_color) std::copy_n(&model.colors[4 * size_t(t)], 4, split.color_t);
  return split;
}

}  // namespace pms
