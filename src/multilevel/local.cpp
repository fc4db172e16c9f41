// Gueziec, Taubin, Horn, Lazarus 1999, "Local refinement" (Fig. 14-15): each collapse has a status, S
// (split) or C (collapsed); an edge V -> I of the DAG forbids V collapsed with I split. The counts of
// those constraints live in hash tables keyed by vertex, as in the paper; only non-zero counts are stored,
// so a refinement that touches few vertices keeps few collapse-constraint entries.
#include "multilevel/local.h"

#include <string>

#include "common/error.h"

namespace pms {
namespace {

std::string str(uint64_t v) { return std::to_string(v); }

}  // namespace

MultilevelRefinement::MultilevelRefinement(const MultilevelDag& dag) : dag_(dag), split_(dag.vertices, 0) {
  std::fill(split_.begin(), split_.begin() + dag.top_vertices, uint8_t(1));
  for (uint32_t v = dag.top_vertices; v < dag.vertices; ++v) {
    const size_t needed = dag.prerequisites_of(v).size();
    if (needed) split_constraints_[v] = uint32_t(needed);
  }
}

uint32_t MultilevelRefinement::count(const CountTable& table, uint32_t v) {
  const auto it = table.find(v);
  return it == table.end() ? 0 : it->second;
}

void MultilevelRefinement::add(CountTable& table, uint32_t v, int delta) {
  uint32_t& c = table[v];
  c = uint32_t(int64_t(c) + delta);
  if (c == 0) table.erase(v);
}

bool MultilevelRefinement::can_split(uint32_t v) const {
  return dag_.is_node(v) && !split_[v] && split_constraints(v) == 0;
}

bool MultilevelRefinement::can_collapse(uint32_t v) const {
  return dag_.is_node(v) && split_[v] && collapse_constraints(v) == 0;
}

void MultilevelRefinement::split(uint32_t v) {
  if (!can_split(v))
    fail("local refinement", "vertex " + str(v) + " cannot be split (" +
                                 (!dag_.is_node(v) ? "not a collapse"
                                  : split_[v]      ? "already split"
                                                   : str(split_constraints(v)) + " prerequisites collapsed") +
                                 ")");
  split_[v] = 1;
  ++split_count_;
  for (uint32_t d : dag_.dependents_of(v)) add(split_constraints_, d, -1);
  for (uint32_t p : dag_.prerequisites_of(v)) add(collapse_constraints_, p, +1);
}

void MultilevelRefinement::collapse(uint32_t v) {
  if (!can_collapse(v))
    fail("local refinement", "vertex " + str(v) + " cannot be collapsed (" +
                                 (!dag_.is_node(v) ? "not a collapse"
                                  : !split_[v]     ? "already collapsed"
                                                   : str(collapse_constraints(v)) + " dependents split") +
                                 ")");
  split_[v] = 0;
  --split_count_;
  for (uint32_t d : dag_.dependents_of(v)) add(split_constraints_, d, +1);
  for (uint32_t p : dag_.prerequisites_of(v)) add(collapse_constraints_, p, -1);
}

void MultilevelRefinement::close_over_prerequisites(std::span<const uint32_t> wanted,
                                                    std::vector<uint8_t>& mark) const {
  std::vector<uint32_t> stack;
  for (uint32_t v : wanted)
    if (dag_.is_node(v) && !mark[v]) {
      mark[v] = 1;
      stack.push_back(v);
    }
  while (!stack.empty()) {
    const uint32_t v = stack.back();
    stack.pop_back();
    for (uint32_t p : dag_.prerequisites_of(v))
      if (!mark[p]) {
        mark[p] = 1;
        stack.push_back(p);
      }
  }
}

// Kahn's algorithm on the counts themselves. Collapsing: a split node nothing kept needs has only
// dependents that are leaving too, so its collapse constraints fall to zero once they are collapsed.
// Splitting: a kept node's collapsed prerequisites are all kept, so its split constraints fall to zero once
// they are split. A node is queued when its count reaches zero, which happens once.
void MultilevelRefinement::change_status(bool splitting, const std::vector<uint8_t>& kept,
                                         std::vector<uint32_t>& done) {
  const auto ready_to_change = [&](uint32_t v) {
    return splitting ? kept[v] && !split_[v] && split_constraints(v) == 0
                     : !kept[v] && split_[v] && collapse_constraints(v) == 0;
  };
  std::vector<uint32_t> ready;
  for (uint32_t v = dag_.top_vertices; v < dag_.vertices; ++v)
    if (ready_to_change(v)) ready.push_back(v);
  while (!ready.empty()) {
    const uint32_t v = ready.back();
    ready.pop_back();
    splitting ? split(v) : collapse(v);
    done.push_back(v);
    for (uint32_t u : splitting ? dag_.dependents_of(v) : dag_.prerequisites_of(v))
      if (ready_to_change(u)) ready.push_back(u);
  }
}

MultilevelRefinement::Changes MultilevelRefinement::refine_to(std::span<const uint32_t> wanted) {
  std::vector<uint8_t> kept(dag_.vertices, 0);
  close_over_prerequisites(wanted, kept);
  Changes changes;
  change_status(false, kept, changes.collapses);
  change_status(true, kept, changes.splits);
  return changes;
}

uint64_t MultilevelRefinement::memory_bytes() const {
  // A node per entry (key, count, next pointer, cached hash) plus the bucket array.
  const auto table_bytes = [](const CountTable& t) {
    return uint64_t(t.size()) * (2 * sizeof(uint32_t) + 2 * sizeof(void*)) + uint64_t(t.bucket_count()) * sizeof(void*);
  };
  return split_.size() + table_bytes(split_constraints_) + table_bytes(collapse_constraints_);
}

}  // namespace pms
