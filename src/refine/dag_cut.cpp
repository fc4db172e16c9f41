// Maintaining the fronts Fc and Fs of a DAG cut by per-node counters (Zheng & Chan 2006 §3, Fig. 1):
// splitting a node moves it from Fs to Fc, takes its DAG parents out of Fc (they now have a split child)
// and brings into Fs the DAG children whose last collapsed parent it was; collapsing is the mirror image.
#include "refine/dag_cut.h"

#include <algorithm>

#include "common/error.h"

namespace pms {
namespace {

constexpr const char* kWhere = "dag cut";

// A session's first answer (the converged cut) fills the queues far beyond what a frame of N operations
// needs: give back the room once they hold less than a quarter of it (amortized: O(size) when it happens).
void shrink(std::vector<uint32_t>& v) {
  if (v.capacity() > 4 * v.size() + 1024) v.shrink_to_fit();
}

}  // namespace

DagCut::DagCut(const Dag& dag, uint32_t inline_limit) : dag_(&dag), state_(dag.size(), 0) {
  init_wide(inline_limit);
  recount();
}

DagCut::DagCut(const Dag& dag, std::span<const uint32_t> split, uint32_t inline_limit)
    : dag_(&dag), state_(dag.size(), 0) {
  init_wide(inline_limit);
  for (uint32_t n : split) {
    if (n >= dag.size()) fail(kWhere, "a split node out of range");
    state_[n] |= kSplit;
  }
  for (uint32_t n : split) {
    const uint32_t hp = dag.hierarchy_parent(n);
    if (hp != kNone && !is_split(hp)) fail(kWhere, "a split node below a collapsed one: not a cut");
    for (uint32_t p : dag.parents(n))
      if (!is_split(p)) fail(kWhere, "a split node whose dependency is collapsed: not a cut");
  }
  recount();
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

// Counters, front sizes, triangles and queues from the split bits alone.
void DagCut::recount() {
  const Dag& dag = *dag_;
  triangles_ = dag.base_faces();
  split_count_ = fc_size_ = fs_size_ = 0;
  for (uint32_t n = 0; n < dag.size(); ++n) {
    uint32_t count = 0;
    if (is_split(n)) {
      for (uint32_t c : dag.children(n)) count += is_split(c);
      triangles_ += dag.faces(n);
      ++split_count_;
    } else {
      for (uint32_t p : dag.parents(n)) count += !is_split(p);
    }
    set_counter(n, count);
    enter_fronts(n);
  }
  for (uint32_t n = 0; n < dag.size(); ++n) {
    if (in_fc(n)) enqueue(collapse_queue_, n, kQueuedC);
    if (is_candidate(n)) enqueue(split_queue_, n, kQueuedS);
  }
}

void DagCut::enqueue(Queue& q, uint32_t n, uint8_t bit) {
  if (state_[n] & bit) return;
  state_[n] |= bit;
  q.items.push_back(n);
}

void DagCut::split(uint32_t n) {
  if (!in_fs(n)) fail(kWhere, "split of a node not in Fs");
  const Dag& dag = *dag_;
  leave_fronts(n);
  state_[n] |= kSplit;  // counter stays 0: its children are collapsed, since they need it
  enter_fronts(n);
  for (uint32_t p : dag.parents(n)) {
    leave_fronts(p);
    add_counter(p, 1);
    enter_fronts(p);
  }
  for (uint32_t c : dag.children(n)) {
    leave_fronts(c);
    add_counter(c, -1);
    enter_fronts(c);
    if (in_fs(c) && is_candidate(c)) enqueue(split_queue_, c, kQueuedS);
  }
  for (int k = 0; k < 2; ++k) {
    const uint32_t c = dag.hierarchy_child(n, k);
    if (c != kNone) enqueue(split_queue_, c, kQueuedS);
  }
  enqueue(collapse_queue_, n, kQueuedC);
  triangles_ += dag.faces(n);
  ++split_count_;
}

void DagCut::collapse(uint32_t n) {
  if (!in_fc(n)) fail(kWhere, "collapse of a node not in Fc");
  const Dag& dag = *dag_;
  leave_fronts(n);
  state_[n] &= uint8_t(~kSplit);  // counter 0 either way: no split child before, no collapsed parent now
  enter_fronts(n);
  for (uint32_t p : dag.parents(n)) {
    leave_fronts(p);
    add_counter(p, -1);
    enter_fronts(p);
    if (in_fc(p)) enqueue(collapse_queue_, p, kQueuedC);
  }
  for (uint32_t c : dag.children(n)) {
    leave_fronts(c);
    add_counter(c, 1);
    enter_fronts(c);
  }
  enqueue(split_queue_, n, kQueuedS);
  triangles_ -= dag.faces(n);
  --split_count_;
}

template <class InFront>
uint32_t DagCut::pop(Queue& q, uint8_t bit, InFront in_front) {
  while (q.head < q.items.size()) {
    const uint32_t n = q.items[q.head++];
    state_[n] &= uint8_t(~bit);
    if (q.head > 4096 && 2 * q.head > q.items.size()) {  // amortized: drop the consumed half
      q.items.erase(q.items.begin(), q.items.begin() + ptrdiff_t(q.head));
      q.head = 0;
      shrink(q.items);
    }
    if (in_front(n)) return n;
  }
  return kNone;
}

template <class InFront>
std::span<const uint32_t> DagCut::compact(Queue& q, uint8_t bit, InFront in_front) {
  size_t kept = 0;
  for (size_t i = q.head; i < q.items.size(); ++i) {
    const uint32_t n = q.items[i];
    if (in_front(n)) q.items[kept++] = n;
    else state_[n] &= uint8_t(~bit);
  }
  q.items.resize(kept);
  q.head = 0;
  shrink(q.items);
  return q.items;
}

uint32_t DagCut::pop_collapse() {
  return pop(collapse_queue_, kQueuedC, [this](uint32_t n) { return in_fc(n); });
}
uint32_t DagCut::pop_split() {
  return pop(split_queue_, kQueuedS, [this](uint32_t n) { return is_candidate(n); });
}
std::span<const uint32_t> DagCut::collapse_front() {
  return compact(collapse_queue_, kQueuedC, [this](uint32_t n) { return in_fc(n); });
}
std::span<const uint32_t> DagCut::split_front() {
  return compact(split_queue_, kQueuedS, [this](uint32_t n) { return is_candidate(n); });
}

void DagCut::trim_split_queue() {
  if (split_queue_size() <= 2 * split_queue_trimmed_ + 1024) return;
  split_queue_trimmed_ = split_front().size();
}

void DagCut::mark(uint32_t n) {
  if (state_[n] & kMark) return;
  state_[n] |= kMark;
  marked_.push_back(n);
}

void DagCut::clear_marks() {
  for (uint32_t n : marked_) state_[n] &= uint8_t(~kMark);
  marked_.clear();
  shrink(marked_);
}

bool DagCut::check(std::string* why) const {
  auto bad = [&](const std::string& what, uint32_t n) {
    if (why) *why = what + " at node " + std::to_string(n);
    return false;
  };
  const Dag& dag = *dag_;
  uint64_t triangles = dag.base_faces();
  uint32_t splits = 0, fc = 0, fs = 0;
  std::vector<uint8_t> queued_c(dag.size(), 0), queued_s(dag.size(), 0);
  for (size_t i = collapse_queue_.head; i < collapse_queue_.items.size(); ++i) ++queued_c[collapse_queue_.items[i]];
  for (size_t i = split_queue_.head; i < split_queue_.items.size(); ++i) ++queued_s[split_queue_.items[i]];
  for (uint32_t n = 0; n < dag.size(); ++n) {
    uint32_t count = 0;
    if (is_split(n)) {
      for (uint32_t p : dag.parents(n))
        if (!is_split(p)) return bad("a split node with a collapsed DAG parent", n);
      const uint32_t hp = dag.hierarchy_parent(n);
      if (hp != kNone && !is_split(hp)) return bad("a split node with a collapsed hierarchy parent", n);
      for (uint32_t c : dag.children(n)) count += is_split(c);
      triangles += dag.faces(n);
      ++splits;
    } else {
      for (uint32_t p : dag.parents(n)) count += !is_split(p);
    }
    if (count != counter(n)) return bad("counter " + std::to_string(counter(n)) + " != recount " + std::to_string(count), n);
    fc += in_fc(n);
    fs += in_fs(n);
    if (queued_c[n] > 1 || queued_s[n] > 1) return bad("queued twice", n);
    if (bool(queued_c[n]) != bool(state_[n] & kQueuedC) || bool(queued_s[n]) != bool(state_[n] & kQueuedS))
      return bad("queue bit without its entry or the reverse", n);
    if (in_fc(n) && !queued_c[n]) return bad("an Fc node not queued", n);
    if (is_candidate(n) && !queued_s[n]) return bad("a split candidate not queued", n);
  }
  if (triangles != triangles_) return bad("triangle count", 0);
  if (splits != split_count_ || fc != fc_size_ || fs != fs_size_) return bad("front sizes", 0);
  return true;
}

size_t DagCut::memory_bytes() const {
  return state_.capacity() + wide_nodes_.capacity() * 4 + wide_counters_.capacity() * 2 +
         4 * (collapse_queue_.items.capacity() + split_queue_.items.capacity() + marked_.capacity());
}

}  // namespace pms
