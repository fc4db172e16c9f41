#include "server/compact_front.h"

#include <stdexcept>

namespace pms {
namespace {

// The breadth-first queue of split nodes, kept per thread: coding a front allocates nothing once it has
// seen a front that large, and no session holds it.
std::vector<uint32_t>& split_queue() {
  thread_local std::vector<uint32_t> queue;
  queue.clear();
  return queue;
}

// A split node waits in the queue for its children to be coded: its first_child entry is fetched while it
// waits (the nodes of a front are spread over the whole array, so each is a cache miss otherwise).
void enqueue(std::vector<uint32_t>& queue, const ModelData& model, uint32_t node) {
  __builtin_prefetch(&model.first_child[node]);
  queue.push_back(node);
}

class BitWriter {
 public:
  explicit BitWriter(std::vector<uint64_t>& words) : words_(words) {}
  // Appends the low `count` bits of `bits` (count <= 2).
  void put(uint64_t bits, unsigned count) {
    const unsigned at = unsigned(bits_ % 64);
    if (at == 0) words_.push_back(0);
    words_.back() |= bits << at;
    if (at + count > 64) words_.push_back(bits >> (64 - at));
    bits_ += count;
  }
  uint64_t bits() const { return bits_; }

 private:
  std::vector<uint64_t>& words_;
  uint64_t bits_ = 0;
};

[[noreturn]] void not_a_front() { throw std::logic_error("CompactFront: the tags are not a front of the forest"); }

}  // namespace

CompactFront::CompactFront(const ModelData& model, const ActiveTags& tags) {
  std::vector<uint64_t> words;
  words.reserve(size_t(2 * tags.active_count() / 64 + 2));
  BitWriter out(words);
  std::vector<uint32_t>& queue = split_queue();
  for (uint32_t r = 0; r < model.root_count; ++r) {
    const bool split = !tags.is_active(r);
    out.put(split, 1);
    if (split) enqueue(queue, model, r);
  }
  // A node the walk reaches (a root, or a child of a split node) is on the front or split: a split leaf
  // means the tags miss a front node, and more active nodes than the walk met, that they hold one below it.
  for (size_t i = 0; i < queue.size(); ++i) {
    const uint32_t child = model.first_child[queue[i]];
    if (child == kNone) not_a_front();
    const bool split_t = !tags.is_active(child), split_u = !tags.is_active(child + 1);
    out.put(uint64_t(split_t) | uint64_t(split_u) << 1, 2);
    if (split_t) enqueue(queue, model, child);
    if (split_u) enqueue(queue, model, child + 1);
  }
  active_ = size_t(out.bits() - queue.size());  // every node the walk met that is not split
  if (active_ != tags.active_count()) not_a_front();
  bits_ = out.bits();
  lowest_ = tags.win_min();
  highest_ = tags.win_max();
  words_.assign(words.begin(), words.end());  // exactly its size: a session holds it between VIEWs
}

ActiveTags CompactFront::tags(const ModelData& model) const {
  std::vector<uint32_t>& queue = split_queue();
  ActiveTags tags;
  tags.reserve_window(lowest_, highest_);
  uint64_t at = 0;
  const auto bit = [&] {
    const bool set = (words_[at / 64] >> (at % 64)) & 1;
    ++at;
    return set;
  };
  for (uint32_t r = 0; r < model.root_count && at < bits_; ++r) {
    if (bit()) enqueue(queue, model, r);
    else tags.activate(r);
  }
  for (size_t i = 0; i < queue.size() && at + 2 <= bits_; ++i) {
    const uint32_t child = model.first_child[queue[i]];
    for (const uint32_t c : {child, child + 1}) {
      if (bit()) enqueue(queue, model, c);
      else tags.activate(c);
    }
  }
  return tags;
}

}  // namespace pms
