// Windowed active tags (kim-lee-kobbelt §6.1): a session's vertex front on the server as one bit per
// node of the breadth-first packed hierarchy, stored only between win_min and win_max. A split
// clears a parent's bit and sets its children's, whose indices are larger (parents precede their
// children in the array), so the window only moves right: words fall off the left end and new ones
// are appended on the right. The memory is the window, not the model.
#pragma once
#include <bit>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace pms {

class ActiveTags {
 public:
  ActiveTags() = default;
  // The front of the base mesh: the roots, nodes [0, root_count).
  explicit ActiveTags(uint32_t root_count);

  bool is_active(uint32_t node) const {
    const uint64_t w = node / 64;
    if (w < first_word_ || w >= first_word_ + words_.size()) return false;
    return (words_[w - first_word_] >> (node % 64)) & 1;
  }
  // Sizes an empty set's window for nodes [lo, hi] at once: a resume then activates its leaves in any
  // order without growing the window on the left.
  void reserve_window(uint32_t lo, uint32_t hi);
  void activate(uint32_t node);
  void deactivate(uint32_t node);
  // A split moves the front below `node`: it leaves, its children (first_child, first_child + 1) come in.
  void split(uint32_t node, uint32_t first_child) {
    deactivate(node);
    activate(first_child);
    activate(first_child + 1);
  }

  // Lowest and highest active node; win_min > win_max when nothing is active.
  uint32_t win_min() const;
  uint32_t win_max() const;
  size_t active_count() const { return active_; }
  // Bytes held for the bits (the capacity, not only the window).
  size_t memory_bytes() const { return words_.capacity() * sizeof(uint64_t); }

  // The first active node >= from, or UINT32_MAX. Walking the front with next_active(n + 1) visits
  // nodes activated behind the cursor too, since they always lie to its right (SelectiveStreaming).
  uint32_t next_active(uint32_t from) const;

 private:
  void drop_leading_zero_words();

  uint64_t first_word_ = 0;      // index of words_[0] in the whole bit array
  std::vector<uint64_t> words_;  // the window, word-aligned
  size_t active_ = 0;
};

}  // namespace pms
