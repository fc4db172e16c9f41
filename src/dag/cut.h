// One cut of the DAG of operations (Zheng & Chan 2006 §3, Fig. 1): which nodes are split, a counter per
// node, and the two fronts kept incrementally. A split node's counter is the number of its split DAG
// children (0: in Fc, legal to collapse); a collapsed node's the number of its split DAG parents (all of
// them: in Fs, legal to split). So the base mesh is all zeros, and a return to it is a clear of the arrays. Each front
// is a bit per node, swept in node order (depth, then deviation) from a cursor that outlives a frame: the linear and
// constant-time traversals continue where they stopped. This dense form is a traversal's working copy (a per-thread
// scratch, dag/compact.h); a session keeps its cut between turns as a CompactDagCut, a few bits per split node. Shared
// with the browser build: single-threaded, no std::ranges algorithms, std::format or coroutines.
#pragma once
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "dag/dag.h"

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
  bool in_fs(uint32_t n) const { return !is_split(n) && counter(n) == dag_->parents(n).size(); }
  // Collapsed with its hierarchy parent split (or a root): an active vertex of the mesh that has a split.
  // Every Fs node is one; the others wait for a dependency and split only with it (forced).
  bool is_candidate(uint32_t n) const { return (candidate_bits_[n / 64] >> (n % 64)) & 1; }

  // ADJUST-FRONTS after the operation: counters of the node's DAG parents and children, both fronts.
  // pms::Error unless n is in Fs (split) or Fc (collapse).
  void split(uint32_t n);
  void collapse(uint32_t n);

  uint64_t triangles() const { return triangles_; }
  uint32_t split_count() const { return split_count_; }
  uint32_t fc_size() const { return fc_size_; }
  uint32_t fs_size() const { return fs_size_; }
  uint32_t candidate_count() const { return candidate_count_; }

  // The fronts in node order: the first Fc node / split candidate (Fs and the waiting ones) >= from, or
  // kNone.
  uint32_t next_fc(uint32_t from) const { return next_bit(fc_bits_, from); }
  uint32_t next_candidate(uint32_t from) const { return next_bit(candidate_bits_, from); }
  // The sweeps: the next node of the front from its cursor on, wrapping at the end (kNone when the front is
  // empty); the cursor moves past it. rewind puts the cursor back on a node, so that the next pop starts
  // there.
  uint32_t pop_collapse() { return pop(fc_bits_, collapse_cursor_, collapse_lead_); }
  uint32_t pop_split() { return pop(candidate_bits_, split_cursor_, split_lead_); }
  void rewind_collapse(uint32_t n) { collapse_cursor_ = n; }
  void rewind_split(uint32_t n) { split_cursor_ = n; }
  uint32_t collapse_cursor() const { return collapse_cursor_; }
  uint32_t split_cursor() const { return split_cursor_; }

  // Constant-time's watch list (docs/internals.md, "The DAG of operations"; DagTraverser::consider_watch):
  // split candidates an evaluation found not needing a split yet, each with a key saying when the view is
  // predicted to make it need one, in no order. Kept between frames with the cursors (CompactDagCut), at
  // most DagTraverser::watch_limit entries; watched(n) says whether n has an entry (one at most). Only the
  // constant-time traversal changes it; entries of nodes that are no candidates any more are dropped when
  // the cut is stored.
  struct Watch {
    uint32_t code;  // node | kind << 29
    float key;
    uint32_t node() const { return code & 0x1FFFFFFF; }
    uint32_t kind() const { return code >> 29; }
  };
  std::vector<Watch>& watch() { return watch_; }
  const std::vector<Watch>& watch() const { return watch_; }
  bool watched(uint32_t n) const { return (state_[n] & kWatched) != 0; }
  void set_watched(uint32_t n, bool on) { state_[n] = uint8_t(on ? state_[n] | kWatched : state_[n] & ~kWatched); }

  // One bit per node for a traversal's marks (the priority traversal's justification); clear_marks
  // clears the marked ones.
  bool marked(uint32_t n) const { return (state_[n] & kMark) != 0; }
  // What a traversal reads and writes of node n (its criteria, its state byte), on its way to the cache.
  void prefetch(uint32_t n) const {
    const char* criteria = reinterpret_cast<const char*>(&dag_->criteria(n));
    __builtin_prefetch(criteria);
    __builtin_prefetch(criteria + sizeof(NodeCriteria) - 1);  // 48 B: every other record spans two lines
    __builtin_prefetch(&state_[n], 1);
  }
  void mark(uint32_t n);
  void clear_marks();

  // From the base mesh (nothing split, no mark) to the cut whose split nodes are `split`, each once:
  // O(split nodes × degree). pms::Error, leaving the base mesh, for a node out of range or listed twice, or
  // a set that is not a cut.
  void load(std::span<const uint32_t> split);
  // Back to the base mesh, cursors at 0: a clear of the state and the two bit arrays (~1.25 B per node).
  void reset();

  // Audit for tests: counters, fronts, cursors and the triangle count equal a recount from scratch, every
  // split node's DAG parents and hierarchy parent are split. On failure `why` (if given) says what.
  bool check(std::string* why) const;
  size_t memory_bytes() const;

 private:
  // The state byte: split, marked, 4-bit counter (kWide: the counter is in the side table).
  static constexpr uint8_t kSplit = 0x80, kWatched = 0x40, kMark = 0x10, kCounter = 0x0F;
  static constexpr uint8_t kWide = 0x0F;
  static_assert(kInlineLimit < kWide && Dag::kMaxChildren <= UINT16_MAX);
  static uint32_t next_bit(const std::vector<uint64_t>& bits, uint32_t from);
  static constexpr int kSweepLead = 8;
  uint32_t pop(const std::vector<uint64_t>& bits, uint32_t& cursor, uint32_t& lead);
  void init_wide(uint32_t inline_limit);
  uint32_t wide_counter(uint32_t n) const;
  uint16_t& wide_slot(uint32_t n);
  void set_counter(uint32_t n, uint32_t value);
  void add_counter(uint32_t n, int delta);
  void set_candidate(uint32_t n, bool on);
  void recount();
  void enter_fronts(uint32_t n);

  const Dag* dag_;
  std::vector<uint8_t> state_;
  std::vector<uint64_t> fc_bits_, candidate_bits_;  // a bit per node: in Fc, a split candidate
  std::vector<uint32_t> wide_nodes_;                // ascending: the nodes whose counters are in the side table
  std::vector<uint16_t> wide_counters_;             // theirs
  std::vector<uint32_t> marked_;
  std::vector<Watch> watch_;
  uint64_t triangles_ = 0;
  uint32_t split_count_ = 0, fc_size_ = 0, fs_size_ = 0, candidate_count_ = 0;
  uint32_t base_fs_ = 0;  // Fs of the base mesh: the nodes without a DAG parent (the roots)
  uint32_t collapse_cursor_ = 0, split_cursor_ = 0;
  uint32_t collapse_lead_ = kNone, split_lead_ = kNone;  // the last node each sweep prefetched
};

// A cut as the mesh a DAG client holds (its resume front, docs/internals.md "The DAG mode"): the vertices of
// the cut's mesh, tree by tree in preorder. Back: each leaf of a complete front closes the inner nodes whose
// subtree ends at it in preorder (the climb through v_u children, at most 63 steps), so over the whole front
// every inner node is appended once, as a DAG node.
std::vector<VertexId> cut_front(const ModelData& model, const DagCut& cut);
void append_closed_splits(const ModelData& model, const Dag& dag, uint32_t leaf, std::vector<uint32_t>& split);

}  // namespace pms
