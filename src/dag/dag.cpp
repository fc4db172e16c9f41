// Building the DAG of vsplit / ecol operations (Zheng & Chan 2005 [19 of the 2006 paper]) from a packed
// vertex hierarchy with fundamental cut vertices (Kim & Lee 2001). Truly selective refinement asks two
// things of a split of v_s: v_s is active (its hierarchy parent is split), and ActiveAncestor(v̂_l) !=
// ActiveAncestor(v̂_r), which holds exactly when the deepest common ancestor w of v̂_l and v̂_r is split.
// A collapse is legal when the cut without the node still meets both for every split node, i.e. when no
// node depending on it is split. So the candidate edges are parent -> node and w -> node; the ones another
// path implies are dropped (the transitive reduction: w an ancestor of the node, or w required by the
// parent's own requirements, or the parent by w's).
#include "dag/dag.h"

#include <algorithm>
#include <atomic>
#include <chrono>

#include "common/error.h"
#include "spm/refine_info.h"
#include "spm/vertex_id.h"

namespace pms {
namespace {

constexpr const char* kWhere = "dag";

// The deepest common ancestor of two leaves of one tree (model indices); climbs the parent links.
uint32_t common_ancestor(const ModelData& model, uint32_t a, uint32_t b) {
  int da = model.id(a).depth(), db = model.id(b).depth();
  for (; da > db; --da) a = model.parent[a];
  for (; db > da; --db) b = model.parent[b];
  while (a != b) {
    if (a == kNone || b == kNone) fail(kWhere, "cut vertices without a common ancestor");
    a = model.parent[a];
    b = model.parent[b];
  }
  return a;
}

// The candidate requirements before reduction, per DAG node: hierarchy parent and dependency.
struct RawEdges {
  std::vector<uint32_t> parent, dependency;
  std::vector<uint32_t> stamp;
  uint32_t search = 0;
  std::vector<uint32_t> stack;

  // Whether `target` must be split for `source` to be: it is in the closure of `source` under both
  // kinds of requirement. Every node met has its whole ancestor chain in the closure, so a chain is
  // climbed once per search (stamps) and only dependencies branch.
  bool needs(uint32_t source, uint32_t target) {
    if (++search == 0) {
      std::fill(stamp.begin(), stamp.end(), 0);
      search = 1;
    }
    stack.assign(1, source);
    while (!stack.empty()) {
      uint32_t y = stack.back();
      stack.pop_back();
      for (; y != kNone && stamp[y] != search; y = parent[y]) {
        if (y == target) return true;
        stamp[y] = search;
        if (dependency[y] != kNone) stack.push_back(dependency[y]);
      }
    }
    return false;
  }
};

}  // namespace

Dag::Dag(const ModelData& model, std::span<const float> positions) {
  static std::atomic<uint64_t> built{0};
  serial_ = ++built;
  const auto start = std::chrono::steady_clock::now();
  check_node_arrays(model);
  const size_t count = model.node_count();
  if (!positions.empty() && positions.size() < 3 * count) fail(kWhere, "fewer positions than nodes");
  const float* position = positions.empty() ? model.position.data() : positions.data();
  node_of_.assign(count, kNone);
  for (uint32_t m = 0; m < count; ++m)
    if (!model.is_leaf(m)) {
      if (model.first_child[m] + 1 >= count || model.first_child[m] <= m) fail(kWhere, "bad child link");
      node_of_[m] = uint32_t(model_node_.size());
      model_node_.push_back(m);
    }
  const uint32_t n_nodes = size();
  base_faces_ = model.base_faces.size() / 3;
  RawEdges raw;
  raw.parent.assign(n_nodes, kNone);
  raw.dependency.assign(n_nodes, kNone);
  raw.stamp.assign(n_nodes, 0);
  hierarchy_parent_.assign(n_nodes, kNone);
  hierarchy_child_.resize(2 * size_t(n_nodes));
  faces_.resize(n_nodes);
  criteria_.resize(n_nodes);
  for (uint32_t n = 0; n < n_nodes; ++n) {
    const uint32_t m = model_node_[n];
    const uint32_t p = model.parent[m];
    if (p != kNone && (p >= count || node_of_[p] == kNone)) fail(kWhere, "bad parent link");
    hierarchy_parent_[n] = p == kNone ? kNone : node_of_[p];
    if (p == kNone) roots_.push_back(n);
    raw.parent[n] = hierarchy_parent_[n];
    for (int k = 0; k < 2; ++k)
      hierarchy_child_[2 * size_t(n) + uint32_t(k)] = node_of_[model.first_child[m] + uint32_t(k)];
    const uint32_t cl = model.cut_left[m], cr = model.cut_right[m];
    if ((cl != kNone && (cl >= count || !model.is_leaf(cl))) || (cr != kNone && (cr >= count || !model.is_leaf(cr))))
      fail(kWhere, "a cut vertex that is not a leaf");
    if (cl == kNone && cr == kNone) fail(kWhere, "a split without cut vertices");
    faces_[n] = uint8_t((cl != kNone) + (cr != kNone));
    criteria_[n] = node_criteria(&position[3 * size_t(m)], dequantize_refine(model.refine[m], model.scale));
    if (cl == kNone || cr == kNone || model.tree_id[cl] != model.tree_id[cr]) continue;  // v_l != v_r always
    if (cl == cr) fail(kWhere, "equal cut vertices");
    const uint32_t w = common_ancestor(model, cl, cr);
    if (is_ancestor_or_self(model.id(w), model.id(m))) {
      ++stats_.redundant_ancestor;  // split whenever v_s is active
      continue;
    }
    raw.dependency[n] = node_of_[w];
  }
  // Transitive reduction: a node has at most the two candidate in-edges, and an edge is redundant
  // exactly when the other one's closure holds its source.
  std::vector<uint32_t> keep_parent = raw.parent, keep_dependency = raw.dependency;
  for (uint32_t n = 0; n < n_nodes; ++n) {
    const uint32_t p = raw.parent[n], w = raw.dependency[n];
    if (w == kNone || p == kNone) continue;
    if (raw.needs(p, w)) {
      keep_dependency[n] = kNone;
      ++stats_.redundant_dependency;
    } else if (raw.needs(w, p)) {
      keep_parent[n] = kNone;
      ++stats_.redundant_parent;
    }
  }
  in_begin_.assign(size_t(n_nodes) + 1, 0);
  std::vector<uint32_t> out_count(n_nodes, 0);
  for (uint32_t n = 0; n < n_nodes; ++n) {
    for (uint32_t a : {keep_parent[n], keep_dependency[n]})
      if (a != kNone) {
        in_edges_.push_back(a);
        ++out_count[a];
      }
    in_begin_[n + 1] = uint32_t(in_edges_.size());
    stats_.parent_edges += keep_parent[n] != kNone;
    stats_.dependency_edges += keep_dependency[n] != kNone;
  }
  out_begin_.assign(size_t(n_nodes) + 1, 0);
  for (uint32_t n = 0; n < n_nodes; ++n) {
    if (out_count[n] > kMaxChildren) fail(kWhere, "a node with more dependents than a cut can count");
    stats_.max_children = std::max(stats_.max_children, out_count[n]);
    out_begin_[n + 1] = out_begin_[n] + out_count[n];
  }
  out_edges_.resize(in_edges_.size());
  std::vector<uint32_t> fill(out_begin_.begin(), out_begin_.end() - 1);
  for (uint32_t n = 0; n < n_nodes; ++n)
    for (uint32_t a : parents(n)) out_edges_[fill[a]++] = n;
  // A cycle (possible only in a hand-made model) would leave its nodes never splittable: refuse it.
  std::vector<uint32_t> pending(n_nodes), ready;
  for (uint32_t n = 0; n < n_nodes; ++n)
    if ((pending[n] = uint32_t(parents(n).size())) == 0) ready.push_back(n);
  size_t ordered = 0;
  while (!ready.empty()) {
    const uint32_t n = ready.back();
    ready.pop_back();
    ++ordered;
    for (uint32_t c : children(n))
      if (--pending[c] == 0) ready.push_back(c);
  }
  if (ordered != n_nodes) fail(kWhere, "the split dependencies form a cycle");
  if (!criteria_.empty()) {
    float low[3], high[3];
    for (int k = 0; k < 3; ++k) low[k] = high[k] = criteria_[0].p[k];
    for (const NodeCriteria& c : criteria_)
      for (int k = 0; k < 3; ++k) {
        low[k] = std::min(low[k], c.p[k]);
        high[k] = std::max(high[k], c.p[k]);
      }
    for (int k = 0; k < 3; ++k) centre_[k] = 0.5f * (low[k] + high[k]);
  }
  stats_.nodes = n_nodes;
  stats_.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

size_t Dag::memory_bytes() const {
  return 4 * (model_node_.size() + node_of_.size() + hierarchy_parent_.size() + roots_.size() +
              hierarchy_child_.size() + in_begin_.size() + in_edges_.size() + out_begin_.size() + out_edges_.size()) +
         faces_.size() + criteria_.size() * sizeof(NodeCriteria);
}

}  // namespace pms
