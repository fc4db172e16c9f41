// The dependency filter (dependency_filter.h): a split's fundamental cut vertices climbed to their deepest
// common ancestor, on every core.
#include "spm/dependency_filter.h"

#include <algorithm>

#include "common/parallel.h"
#include "spm/vertex_id.h"

namespace pms {

DependencyFilter::DependencyFilter(const ModelData& model) {
  bits_.assign((model.node_count() + 63) / 64, 0);
  const auto depth = [&](uint32_t n) { return VertexId{0, model.node_id[n]}.depth(); };
  const auto ancestor_at = [&](uint32_t n, int d) {
    while (n != kNone && depth(n) > d) n = model.parent[n];
    return n;
  };
  // Ranges of whole words, so threads never share one.
  const size_t words = bits_.size();
  for_each_range(words, 1024, [&](size_t begin, size_t end) {
    for (size_t v = begin * 64; v < std::min<size_t>(end * 64, model.node_count()); ++v) {
      uint32_t l = model.cut_left[v], r = model.cut_right[v];
      if (model.is_leaf(uint32_t(v)) || l == kNone || r == kNone || model.tree_id[l] != model.tree_id[r]) continue;
      const int common = std::min(depth(l), depth(r));
      l = ancestor_at(l, common);
      r = ancestor_at(r, common);
      while (l != r) {
        l = model.parent[l];
        r = model.parent[r];
      }
      const bool above_v = depth(l) < depth(uint32_t(v)) && ancestor_at(uint32_t(v), depth(l)) == l;
      if (!above_v) bits_[v / 64] |= uint64_t(1) << (v % 64);
    }
  });
}

}  // namespace pms
