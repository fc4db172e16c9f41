// A DAG cut between traversals, in a few bits per split node (docs/internals.md, "Per-session memory"): the
// split set as the hierarchy's shape, top down, and the two sweeps' cursors. Counters and fronts are not
// kept: they follow from the split set and the edges. A traversal runs on a dense DagCut that this thread
// keeps per model (LoadedDagCut), decoded into at the start of a turn and encoded back at its end, so a
// server's sessions hold only this form and each I/O thread one dense cut per model it serves.
// Shared with the browser build: single-threaded, no std::ranges algorithms, std::format or coroutines.
#pragma once
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "dag/cut.h"
#include "dag/dag.h"

namespace pms {

// The code: a bit per root (split?), then, breadth first over the split nodes from the roots, a bit per
// hierarchy child that is a DAG node (split?); leaf children are implied. At most 2 bits per split node
// plus one per root.
class CompactDagCut {
 public:
  CompactDagCut() = default;  // the base mesh (an empty code)
  // Encodes `cut`, appending its split nodes (in the code's order, the walk's queue) to `split` when given.
  explicit CompactDagCut(const DagCut& cut, std::vector<uint32_t>* split = nullptr);

  // Appends the split nodes in the code's order (parents before hierarchy children). pms::Error for a code
  // that is not of `dag` (it ends early or goes on).
  void split_nodes(const Dag& dag, std::vector<uint32_t>& out) const;
  // A dense copy (tests, benches: a session's cut).
  DagCut dense(const Dag& dag) const;

  uint32_t split_count() const { return split_count_; }
  uint64_t triangles() const { return triangles_; }
  uint64_t code_bits() const { return bits_; }
  const std::vector<DagCut::Watch>& watch() const { return watch_; }
  size_t memory_bytes() const {
    return words_.capacity() * sizeof(uint64_t) + watch_.capacity() * sizeof(DagCut::Watch);
  }

 private:
  friend class LoadedDagCut;
  std::vector<uint64_t> words_;
  uint64_t bits_ = 0;
  uint64_t triangles_ = 0;
  uint32_t split_count_ = 0;
  uint32_t collapse_cursor_ = 0, split_cursor_ = 0;
  std::vector<DagCut::Watch> watch_;  // constant-time's watch list, DagCut::watch()
};

// This thread's dense cut of a DAG, loaned for one turn: loaded with a compact cut (or a split set, as a
// resume rebuilds one), returned to the base mesh when the loan ends, whatever happened in between. A
// thread keeps one per DAG it served lately (a few); a second loan of the same DAG on the same thread
// while the first is alive gets a cut of its own.
class LoadedDagCut {
 public:
  LoadedDagCut(const Dag& dag, const CompactDagCut& compact);
  // pms::Error unless `split` is a cut (DagCut::load).
  LoadedDagCut(const Dag& dag, std::span<const uint32_t> split);
  ~LoadedDagCut();
  LoadedDagCut(const LoadedDagCut&) = delete;
  LoadedDagCut& operator=(const LoadedDagCut&) = delete;

  DagCut& cut() { return *cut_; }
  // Ends the loan: the cut as it is now (cursors included), and the dense cut back to the base mesh.
  CompactDagCut store();

  // The dense cuts this thread keeps (not per session).
  static size_t thread_scratch_bytes();

 private:
  struct Slot;
  static std::vector<std::unique_ptr<Slot>>& thread_slots();
  void borrow(const Dag& dag);
  void give_back();
  Slot* slot_ = nullptr;
  DagCut* cut_ = nullptr;      // slot_'s
  std::unique_ptr<Slot> own_;  // when this thread's slot of the DAG is on loan already
};

}  // namespace pms
