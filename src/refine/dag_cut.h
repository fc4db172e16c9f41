// One cut of the DAG of operations (Zheng & Chan 2006 §3, Fig. 1): which nodes are split, a counter per
// node, and the two fronts kept incrementally. A split node's counter is the number of its split DAG
// children (0: in Fc, legal to collapse); a collapsed node's the number of its collapsed DAG parents
// (0: in Fs, legal to split). The nodes of the two fronts sit in FIFO queues that outlive a frame (the
// linear and constant-time traversals continue where they stopped); a queue may hold nodes that left
// its front since, dropped when met.
// Shared with the browser build: single-threaded, no std::ranges algorithms, std::format or coroutines.
#pragma once
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "refine/dag.h"

namespace pms {

class DagCut {
 public:
  // A node's counter lives in its state byte when the node has at most `inline_limit` (<= 14) DAG
  // children, else in a side table (no node of the models measured has more than 4; tests lower the
  // limit to exercise the table).
  static constexpr uint32_t kInlineLimit = 14;

  // The base mesh: nothing split. `dag` must outlive the cut.
  explicit DagCut(const Dag& dag, uint32_t inline_limit = kInlineLimit);
  // The cut whose split nodes are `split` (any order, duplicates allowed), e.g. rebuilt from what a
  // resuming client holds: pms::Error for a node out of range or a set that is not a cut (a split node
  // whose DAG parent or hierarchy parent is collapsed). O(nodes + edges).
  DagCut(const Dag& dag, std::span<const uint32_t> split, uint32_t inline_limit = kInlineLimit);

  const Dag& dag() const { return *dag_; }
  bool is_split(uint32_t n) const { return (state_[n] & kSplit) != 0; }
  uint32_t counter(uint32_t n) const {
    const uint32_t c = state_[n] & kCounter;
    return c == kWide ? wide_counter(n) : c;
  }
  bool in_fc(uint32_t n) const { return is_split(n) && counter(n) == 0; }
  bool in_fs(uint32_t n) const { return !is_split(n) && counter(n) == 0; }
  // Collapsed with its hierarchy parent split (or a root): an active vertex of the mesh that has a split.
  // Every Fs node is one; the others wait for a dependency and split only with it (forced).
  bool is_candidate(uint32_t n) const {
    const uint32_t p = dag_->hierarchy_parent(n);
    return !is_split(n) && (p == kNone || is_split(p));
  }

  // ADJUST-FRONTS after the operation: counters of the node's DAG parents and children, both fronts
  // and queues. pms::Error unless n is in Fs (split) or Fc (collapse).
  void split(uint32_t n);
  void collapse(uint32_t n);

  uint64_t triangles() const { return triangles_; }
  uint32_t split_count() const { return split_count_; }
  uint32_t fc_size() const { return fc_size_; }
  uint32_t fs_size() const { return fs_size_; }

  // The queues of the two fronts: Fc (collapse) and the split candidates (Fs and the waiting ones).
  // pop returns the first node still in its front, or kNone when the queue is empty; requeue appends a
  // popped node that stays in its front.
  uint32_t pop_collapse();
  uint32_t pop_split();
  void requeue_collapse(uint32_t n) { enqueue(collapse_queue_, n, kQueuedC); }
  void requeue_split(uint32_t n) { enqueue(split_queue_, n, kQueuedS); }
  size_t collapse_queue_size() const { return collapse_queue_.items.size() - collapse_queue_.head; }
  size_t split_queue_size() const { return split_queue_.items.size() - split_queue_.head; }
  // The queued nodes still in their fronts, in queue order (drops the others).
  std::span<const uint32_t> collapse_front();
  std::span<const uint32_t> split_front();
  // Compacts the split queue once it holds twice the entries it held after the last compaction (a
  // traversal that does not pop it calls this; amortized O(1) per operation).
  void trim_split_queue();

  // One bit per node for a traversal's marks (the priority traversal's justification); clear_marks
  // clears the marked ones.
  bool marked(uint32_t n) const { return (state_[n] & kMark) != 0; }
  void mark(uint32_t n);
  void clear_marks();

  // Audit for tests: counters, fronts, queues and the triangle count equal a recount from scratch, every
  // split node's DAG parents and hierarchy parent are split. On failure `why` (if given) says what.
  bool check(std::string* why) const;
  size_t memory_bytes() const;

 private:
  // The state byte: split, queued in Fc's queue, queued in the split queue, marked, 4-bit counter
  // (kWide: the counter is in the side table).
  static constexpr uint8_t kSplit = 0x80, kQueuedC = 0x40, kQueuedS = 0x20, kMark = 0x10, kCounter = 0x0F;
  static constexpr uint8_t kWide = 0x0F;
  static_assert(kInlineLimit < kWide && Dag::kMaxChildren <= UINT16_MAX);
  struct Queue {
    std::vector<uint32_t> items;
    size_t head = 0;
  };
  void enqueue(Queue& q, uint32_t n, uint8_t bit);
  template <class InFront>
  uint32_t pop(Queue& q, uint8_t bit, InFront in_front);
  template <class InFront>
  std::span<const uint32_t> compact(Queue& q, uint8_t bit, InFront in_front);
  void init_wide(uint32_t inline_limit);
  uint32_t wide_counter(uint32_t n) const;
  uint16_t& wide_slot(uint32_t n);
  void set_counter(uint32_t n, uint32_t value);
  void add_counter(uint32_t n, int delta);
  void recount();
  void leave_fronts(uint32_t n) { fc_size_ -= in_fc(n); fs_size_ -= in_fs(n); }
  void enter_fronts(uint32_t n) { fc_size_ += in_fc(n); fs_size_ += in_fs(n); }

  const Dag* dag_;
  std::vector<uint8_t> state_;
  std::vector<uint32_t> wide_nodes_;     // ascending: the nodes whose counters are in the side table
  std::vector<uint16_t> wide_counters_;  // theirs
  Queue collapse_queue_, split_queue_;
  size_t split_queue_trimmed_ = 0;  // entries after the last compaction
  std::vector<uint32_t> marked_;
  uint64_t triangles_ = 0;
  uint32_t split_count_ = 0, fc_size_ = 0, fs_size_ = 0;
};

}  // namespace pms
