// Maintaining the fronts Fc and Fs of a DAG cut by per-node counters (Zheng & Chan 2006 §3, Fig. 1):
// splitting a node moves it from Fs to Fc, takes its DAG parents out of Fc (they now have a split child)
// and brings into Fs the DAG children whose last collapsed parent it was; collapsing is the mirror image.
#include "dag/cut.h"

#include <algorithm>
#include <bit>

#include "common/error.h"

namespace pms {
namespace {

constexpr const char* kWhere = "dag cut";

void set_bit(std::vector<uint64_t>& bits, uint32_t n, bool on) {
  const uint64_t mask = uint64_t(1) << (n % 64);
  uint64_t& word = bits[n / 64];
  word = (word & ~mask) | (on ? mask : 0);
}

}  // namespace

DagCut::DagCut(const Dag& dag, uint32_t inline_limit)
    : dag_(&dag), state_(dag.size(), 0), fc_bits_((dag.size() + 63) / 64, 0), candidate_bits_(fc_bits_.size(), 0) {
  init_wide(inline_limit);
  recount();
}

DagCut::DagCut(const Dag& dag, std::span<const uint32_t> split, uint32_t inline_limit) : DagCut(dag, inline_limit) {
  std::vector<uint32_t> once(split.begin(), split.end());
  std::sort(once.begin(), once.end());
  once.erase(std::unique(once.begin(), once.end()), once.end());
  load(once);
}

void DagCut::init_wide(uint32_t inline_limit) {
  if (inline_limit > kInlineLimit) fail(kWhere, "counters wider than the state byte");
  for (uint32_t n = 0; n < dag_->size(); ++n)
    if (dag_->children(n).size() > inline_limit || dag_->parents(n).size() > inline_limit) {
      wide_nodes_.push_back(n);
      state_[n] = kWide;
    }
  wide_counters_.assign(wide_nodes_.size(), 0);
}

uint32_t DagCut::wide_counter(uint32_t n) const {
  return wide_counters_[size_t(std::lower_bound(wide_nodes_.begin(), wide_nodes_.end(), n) - wide_nodes_.begin())];
}

uint16_t& DagCut::wide_slot(uint32_t n) {
  return wide_counters_[size_t(std::lower_bound(wide_nodes_.begin(), wide_nodes_.end(), n) - wide_nodes_.begin())];
}

void DagCut::set_counter(uint32_t n, uint32_t value) {
  if ((state_[n] & kCounter) == kWide) wide_slot(n) = uint16_t(value);
  else state_[n] = uint8_t((state_[n] & ~kCounter) | value);
}

void DagCut::add_counter(uint32_t n, int delta) {
  if ((state_[n] & kCounter) == kWide) wide_slot(n) = uint16_t(wide_slot(n) + delta);
  else state_[n] = uint8_t(state_[n] + delta);  // stays within the low bits: 0 <= counter <= degree
}

void DagCut::set_candidate(uint32_t n, bool on) {
  candidate_count_ += uint32_t(on) - uint32_t(is_candidate(n));
  set_bit(candidate_bits_, n, on);
}

void DagCut::enter_fronts(uint32_t n) {
  const bool fc = in_fc(n);
  fc_size_ += fc;
  fs_size_ += in_fs(n);
  set_bit(fc_bits_, n, fc);
}

// Counters, fronts and triangles from the split bits alone.
void DagCut::recount() {
  const Dag& dag = *dag_;
  triangles_ = dag.base_faces();
  split_count_ = fc_size_ = fs_size_ = candidate_count_ = 0;
  for (uint32_t n = 0; n < dag.size(); ++n) {
    uint32_t count = 0;
    if (is_split(n)) {
      for (uint32_t c : dag.children(n)) count += is_split(c);
      triangles_ += dag.faces(n);
      ++split_count_;
    } else {
      for (uint32_t p : dag.parents(n)) count += is_split(p);
    }
    set_counter(n, count);
    enter_fronts(n);
    const uint32_t hp = dag.hierarchy_parent(n);
    set_candidate(n, !is_split(n) && (hp == kNone || is_split(hp)));
  }
  if (split_count_ == 0) base_fs_ = fs_size_;
}

// The split bits first (a dependency may come after the node that needs it), then the counters, which only
// grow from the base mesh's zeros, then Fc. The nodes are scattered over the Dag's arrays, so each pass
// fetches ahead: a node's links kLoadLead nodes ahead, its edge lists half as far, its neighbours' state a
// quarter (each stage reads what the one before fetched).
void DagCut::load(std::span<const uint32_t> split) {
  if (split_count_ != 0 || !marked_.empty()) fail(kWhere, "load() needs the base mesh");
  const Dag& dag = *dag_;
  constexpr size_t kLoadLead = 16;
  const auto ahead = [&](size_t i, size_t lead) { return i + lead < split.size() && split[i + lead] < dag.size(); };
  for (size_t i = 0; i < split.size(); ++i) {
    const uint32_t n = split[i];
    if (n >= dag.size()) {
      reset();
      fail(kWhere, "a split node out of range");
    }
    if (ahead(i, kLoadLead)) {
      dag.prefetch_links(split[i + kLoadLead]);
      __builtin_prefetch(&state_[split[i + kLoadLead]], 1);
    }
    if (is_split(n)) continue;
    fs_size_ -= in_fs(n);
    state_[n] |= kSplit;
    set_candidate(n, false);
    ++split_count_;
    triangles_ += dag.faces(n);
  }
  if (split.size() != split_count_) {
    reset();
    fail(kWhere, "load() takes each split node once");
  }
  for (size_t i = 0; i < split.size(); ++i) {
    if (ahead(i, kLoadLead)) dag.prefetch_links(split[i + kLoadLead]);
    if (ahead(i, kLoadLead / 2)) dag.prefetch_edges(split[i + kLoadLead / 2]);
    if (ahead(i, kLoadLead / 4)) {
      const uint32_t next = split[i + kLoadLead / 4];
      for (uint32_t p : dag.parents(next)) __builtin_prefetch(&state_[p], 1);
      for (uint32_t c : dag.children(next)) __builtin_prefetch(&state_[c], 1);
    }
    const uint32_t n = split[i];
    const uint32_t hp = dag.hierarchy_parent(n);
    bool cut = hp == kNone || is_split(hp);
    for (uint32_t p : dag.parents(n)) {
      cut = cut && is_split(p);
      add_counter(p, 1);
    }
    if (!cut) {
      reset();
      fail(kWhere, "a split node below a collapsed one or whose dependency is collapsed: not a cut");
    }
    for (uint32_t c : dag.children(n))
      if (!is_split(c)) {
        add_counter(c, 1);
        fs_size_ += in_fs(c);
      }
    for (int k = 0; k < 2; ++k)
      if (const uint32_t c = dag.hierarchy_child(n, k); c != kNone && !is_split(c)) set_candidate(c, true);
  }
  for (uint32_t n : split) enter_fronts(n);
}

void DagCut::reset() {
  std::fill(state_.begin(), state_.end(), uint8_t(0));
  for (uint32_t n : wide_nodes_) state_[n] = kWide;
  std::fill(wide_counters_.begin(), wide_counters_.end(), uint16_t(0));
  std::fill(fc_bits_.begin(), fc_bits_.end(), uint64_t(0));
  std::fill(candidate_bits_.begin(), candidate_bits_.end(), uint64_t(0));
  candidate_count_ = 0;
  for (uint32_t r : dag_->roots()) set_candidate(r, true);
  marked_.clear();
  watch_.clear();
  triangles_ = dag_->base_faces();
  split_count_ = fc_size_ = 0;
  fs_size_ = base_fs_;
  collapse_cursor_ = split_cursor_ = 0;
  collapse_lead_ = split_lead_ = kNone;
}

// The fronts change only where the operation says they can: a split node's DAG parents are split and
// leave Fc with their first split child; its DAG children are collapsed and enter Fs with their last split
// parent (collapse: the mirror image). enter_fronts' general recount cost twice as much on this hot path.
void DagCut::split(uint32_t n) {
  if (!in_fs(n)) fail(kWhere, "split of a node not in Fs");
  const Dag& dag = *dag_;
  --fs_size_;
  state_[n] |= kSplit;
  set_counter(n, 0);  // its split children: none, they need it
  ++fc_size_;
  set_bit(fc_bits_, n, true);
  set_candidate(n, false);
  for (uint32_t p : dag.parents(n)) {
    if (counter(p) == 0) {
      --fc_size_;
      set_bit(fc_bits_, p, false);
    }
    add_counter(p, 1);
  }
  for (uint32_t c : dag.children(n)) {
    add_counter(c, 1);
    fs_size_ += counter(c) == dag.parents(c).size();
  }
  for (int k = 0; k < 2; ++k)
    if (const uint32_t c = dag.hierarchy_child(n, k); c != kNone) set_candidate(c, true);
  triangles_ += dag.faces(n);
  ++split_count_;
}

void DagCut::collapse(uint32_t n) {
  if (!in_fc(n)) fail(kWhere, "collapse of a node not in Fc");
  const Dag& dag = *dag_;
  --fc_size_;
  set_bit(fc_bits_, n, false);
  state_[n] &= uint8_t(~kSplit);
  set_counter(n, uint32_t(dag.parents(n).size()));  // its split parents: all, since it was split
  ++fs_size_;
  set_candidate(n, true);  // its hierarchy parent is split, since it was
  for (uint32_t p : dag.parents(n)) {
    add_counter(p, -1);
    if (counter(p) == 0) {
      ++fc_size_;
      set_bit(fc_bits_, p, true);
    }
  }
  for (uint32_t c : dag.children(n)) {
    fs_size_ -= counter(c) == dag.parents(c).size();
    add_counter(c, -1);
  }
  for (int k = 0; k < 2; ++k)  // collapsed, as every DAG descendant of an Fc node is
    if (const uint32_t c = dag.hierarchy_child(n, k); c != kNone) set_candidate(c, false);
  triangles_ -= dag.faces(n);
  --split_count_;
}

uint32_t DagCut::next_bit(const std::vector<uint64_t>& bits, uint32_t from) {
  size_t w = from / 64;
  if (w >= bits.size()) return kNone;
  uint64_t word = bits[w] & (~uint64_t(0) << (from % 64));
  while (word == 0) {
    if (++w == bits.size()) return kNone;
    word = bits[w];
  }
  return uint32_t(w * 64 + size_t(std::countr_zero(word)));
}

uint32_t DagCut::pop(const std::vector<uint64_t>& bits, uint32_t& cursor, uint32_t& lead) {
  uint32_t n = next_bit(bits, cursor);
  if (n == kNone) n = next_bit(bits, 0);
  if (n == kNone) return n;
  cursor = n + 1;
  // A front is sparse in node order (a few % of the nodes), so each node the sweep reaches is a cache miss
  // in the criteria its evaluation reads: keep the next kSweepLead on their way (a wrap or a rewind only
  // makes the lead start again from here).
  int steps = 1;
  if (lead == kNone || lead <= n) lead = n, steps = kSweepLead;
  for (; steps > 0; --steps) {
    lead = next_bit(bits, lead + 1);
    if (lead == kNone) break;
    prefetch(lead);
  }
  return n;
}

void DagCut::mark(uint32_t n) {
  if (state_[n] & kMark) return;
  state_[n] |= kMark;
  marked_.push_back(n);
}

void DagCut::clear_marks() {
  for (uint32_t n : marked_) state_[n] &= uint8_t(~kMark);
  marked_.clear();
}

bool DagCut::check(std::string* why) const {
  auto bad = [&](const std::string& what, uint32_t n) {
    if (why) *why = what + " at node " + std::to_string(n);
    return false;
  };
  const Dag& dag = *dag_;
  uint64_t triangles = dag.base_faces();
  uint32_t splits = 0, fc = 0, fs = 0, candidates = 0;
  for (uint32_t n = 0; n < dag.size(); ++n) {
    uint32_t count = 0;
    const uint32_t hp = dag.hierarchy_parent(n);
    if (is_split(n)) {
      for (uint32_t p : dag.parents(n))
        if (!is_split(p)) return bad("a split node with a collapsed DAG parent", n);
      if (hp != kNone && !is_split(hp)) return bad("a split node with a collapsed hierarchy parent", n);
      for (uint32_t c : dag.children(n)) count += is_split(c);
      triangles += dag.faces(n);
      ++splits;
    } else {
      for (uint32_t p : dag.parents(n)) count += is_split(p);
    }
    if (count != counter(n))
      return bad("counter " + std::to_string(counter(n)) + " != recount " + std::to_string(count), n);
    fc += in_fc(n);
    fs += in_fs(n);
    const bool fc_bit = (fc_bits_[n / 64] >> (n % 64)) & 1;
    if (fc_bit != in_fc(n)) return bad("the Fc bit is not the node's state", n);
    if (is_candidate(n) != (!is_split(n) && (hp == kNone || is_split(hp))))
      return bad("the candidate bit is not the node's state", n);
    candidates += is_candidate(n);
    if (marked(n)) return bad("a mark left between traversals", n);
  }
  if (triangles != triangles_) return bad("triangle count", 0);
  if (splits != split_count_ || fc != fc_size_ || fs != fs_size_ || candidates != candidate_count_)
    return bad("front sizes", 0);
  return true;
}

size_t DagCut::memory_bytes() const {
  return state_.capacity() + (fc_bits_.capacity() + candidate_bits_.capacity()) * 8 + wide_nodes_.capacity() * 4 +
         wide_counters_.capacity() * 2 + 4 * marked_.capacity() + watch_.capacity() * sizeof(Watch);
}

std::vector<VertexId> cut_front(const ModelData& model, const DagCut& cut) {
  const Dag& dag = cut.dag();
  std::vector<VertexId> front;
  std::vector<uint32_t> stack;
  for (uint32_t root = model.root_count; root-- > 0;) stack.push_back(root);
  while (!stack.empty()) {
    const uint32_t v = stack.back();
    stack.pop_back();
    const uint32_t n = model.is_leaf(v) ? kNone : dag.node_of(v);
    if (n == kNone || !cut.is_split(n)) {
      front.push_back(model.id(v));
      continue;
    }
    stack.push_back(model.first_child[v] + 1);
    stack.push_back(model.first_child[v]);
  }
  return front;
}

void append_closed_splits(const ModelData& model, const Dag& dag, uint32_t leaf, std::vector<uint32_t>& split) {
  for (uint32_t v = leaf; (model.node_id[v] & 1) && model.node_id[v] > 1;) {  // v_u: its parent's last leaf
    v = model.parent[v];
    split.push_back(dag.node_of(v));
  }
}

}  // namespace pms
