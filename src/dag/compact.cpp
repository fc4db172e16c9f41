// The compact DAG cut's code (the hierarchy's shape over the split nodes, breadth first) and the per-thread
// dense cuts a turn decodes it into.
#include "dag/compact.h"

#include <algorithm>
#include <utility>

#include "common/error.h"

namespace pms {
namespace {

constexpr const char* kWhere = "compact dag cut";
// Dense cuts a thread keeps: one per model it serves lately (each is ~1.3 B per node).
constexpr size_t kThreadSlots = 4;

class BitWriter {
 public:
  explicit BitWriter(std::vector<uint64_t>& words) : words_(words) {}
  void put(bool bit) {
    if (bits_ % 64 == 0) words_.push_back(0);
    words_.back() |= uint64_t(bit) << (bits_ % 64);
    ++bits_;
  }
  uint64_t bits() const { return bits_; }

 private:
  std::vector<uint64_t>& words_;
  uint64_t bits_ = 0;
};

// The split nodes breadth first from the roots; `visit(node, split)` for every root and every hierarchy
// child of a split node that is a DAG node, in the code's order. Splits are appended to `out`.
template <class IsSplit>
void walk_split_nodes(const Dag& dag, std::vector<uint32_t>& out, IsSplit is_split) {
  const size_t first = out.size();
  for (uint32_t r : dag.roots())
    if (is_split(r)) out.push_back(r);
  constexpr size_t kLead = 8;  // the queue's nodes are scattered over the Dag's arrays
  for (size_t i = first; i < out.size(); ++i) {
    if (i + kLead < out.size()) dag.prefetch_links(out[i + kLead]);
    for (int k = 0; k < 2; ++k)
      if (const uint32_t c = dag.hierarchy_child(out[i], k); c != kNone && is_split(c)) out.push_back(c);
  }
}

}  // namespace

CompactDagCut::CompactDagCut(const DagCut& cut, std::vector<uint32_t>* split) {
  std::vector<uint32_t> own;
  std::vector<uint32_t>& nodes = split ? *split : own;
  std::vector<uint64_t> words;
  words.reserve(size_t(cut.split_count() / 32 + cut.dag().roots().size() / 64 + 2));
  BitWriter writer(words);
  walk_split_nodes(cut.dag(), nodes, [&](uint32_t n) {
    writer.put(cut.is_split(n));
    return cut.is_split(n);
  });
  words_ = std::vector<uint64_t>(words.begin(), words.end());  // exactly the code's words
  bits_ = writer.bits();
  triangles_ = cut.triangles();
  split_count_ = cut.split_count();
  collapse_cursor_ = cut.collapse_cursor();
  split_cursor_ = cut.split_cursor();
  size_t live = 0;
  for (const DagCut::Watch& w : cut.watch()) live += cut.is_candidate(w.node());
  watch_.reserve(live);
  for (const DagCut::Watch& w : cut.watch())
    if (cut.is_candidate(w.node())) watch_.push_back(w);
}

// The watch list into a loaded cut: one entry per node, each a split candidate of it.
static void load_watch(DagCut& cut, const std::vector<DagCut::Watch>& watch) {
  std::vector<DagCut::Watch>& into = cut.watch();
  into.clear();
  for (const DagCut::Watch& w : watch)
    if (w.node() < cut.dag().size() && cut.is_candidate(w.node()) && !cut.watched(w.node())) {
      cut.set_watched(w.node(), true);
      into.push_back(w);
    }
}

void CompactDagCut::split_nodes(const Dag& dag, std::vector<uint32_t>& out) const {
  if (bits_ == 0) return;  // a default one: the base mesh
  uint64_t bit = 0;
  walk_split_nodes(dag, out, [&](uint32_t) {
    if (bit >= bits_) fail(kWhere, "the code ends before the cut does");
    const bool split = (words_[bit / 64] >> (bit % 64)) & 1;
    ++bit;
    return split;
  });
  if (bit != bits_) fail(kWhere, "the code goes on after the cut");
}

DagCut CompactDagCut::dense(const Dag& dag) const {
  std::vector<uint32_t> split;
  split_nodes(dag, split);
  DagCut cut(dag, split);
  cut.rewind_collapse(collapse_cursor_);
  cut.rewind_split(split_cursor_);
  load_watch(cut, watch_);
  return cut;
}

struct LoadedDagCut::Slot {
  const Dag* dag = nullptr;
  uint64_t serial = 0;
  std::unique_ptr<DagCut> cut;
  std::vector<uint32_t> split;  // the decoded split nodes
  bool busy = false;
  uint64_t used = 0;  // for eviction: the least recently used goes
};

std::vector<std::unique_ptr<LoadedDagCut::Slot>>& LoadedDagCut::thread_slots() {
  static thread_local std::vector<std::unique_ptr<Slot>> slots;
  return slots;
}

// This thread's slot of `dag` (made, or taking the least recently used one's place), or one of our own
// when it is on loan.
void LoadedDagCut::borrow(const Dag& dag) {
  static thread_local uint64_t clock = 0;
  std::vector<std::unique_ptr<Slot>>& slots = thread_slots();
  Slot* victim = nullptr;
  bool on_loan = false;
  for (const std::unique_ptr<Slot>& s : slots) {
    const bool same = s->dag == &dag && s->serial == dag.serial();
    if (same && !s->busy) slot_ = s.get();
    on_loan |= same && s->busy;
    if (!s->busy && (!victim || s->used < victim->used)) victim = s.get();
  }
  if (!slot_) {
    if (on_loan || (slots.size() >= kThreadSlots && !victim)) {
      own_ = std::make_unique<Slot>();
      slot_ = own_.get();
    } else if (slots.size() < kThreadSlots) {
      slots.push_back(std::make_unique<Slot>());
      slot_ = slots.back().get();
    } else {
      slot_ = victim;
    }
    slot_->cut.reset();  // the old DAG's first: never two dense cuts at once for one slot
    slot_->cut = std::make_unique<DagCut>(dag);
    slot_->dag = &dag;
    slot_->serial = dag.serial();
  }
  slot_->busy = true;
  slot_->used = ++clock;
  cut_ = slot_->cut.get();
}

LoadedDagCut::LoadedDagCut(const Dag& dag, const CompactDagCut& compact) {
  borrow(dag);
  try {
    slot_->split.clear();
    compact.split_nodes(dag, slot_->split);
    slot_->cut->load(slot_->split);
  } catch (...) {
    slot_->busy = false;  // the cut is still the base mesh (load leaves it so)
    throw;
  }
  slot_->cut->rewind_collapse(compact.collapse_cursor_);
  slot_->cut->rewind_split(compact.split_cursor_);
  load_watch(*slot_->cut, compact.watch_);
}

LoadedDagCut::LoadedDagCut(const Dag& dag, std::span<const uint32_t> split) {
  borrow(dag);
  try {
    slot_->cut->load(split);
  } catch (...) {
    slot_->busy = false;
    throw;
  }
}

CompactDagCut LoadedDagCut::store() {
  if (!slot_->busy) fail(kWhere, "a loan stored twice");
  slot_->split.clear();
  const CompactDagCut compact(*slot_->cut, &slot_->split);  // the walk's queue is the thread's too
  give_back();
  return compact;
}

void LoadedDagCut::give_back() {
  slot_->cut->reset();
  slot_->split.clear();  // its capacity is the thread's, for the next turn
  slot_->busy = false;
}

LoadedDagCut::~LoadedDagCut() {
  if (slot_->busy) give_back();
}

size_t LoadedDagCut::thread_scratch_bytes() {
  size_t bytes = 0;
  for (const std::unique_ptr<Slot>& s : thread_slots())
    if (s->cut) bytes += s->cut->memory_bytes() + s->split.capacity() * sizeof(uint32_t);
  return bytes;
}

}  // namespace pms
