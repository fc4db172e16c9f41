#include "server/active_tags.h"

#include <algorithm>

namespace pms {

ActiveTags::ActiveTags(uint32_t root_count) : words_((size_t(root_count) + 63) / 64, 0), active_(root_count) {
  for (uint32_t w = 0; w < root_count / 64; ++w) words_[w] = ~uint64_t(0);
  if (root_count % 64) words_.back() = (uint64_t(1) << (root_count % 64)) - 1;
}

void ActiveTags::reserve_window(uint32_t lo, uint32_t hi) {
  if (active_ != 0 || lo > hi) return;
  first_word_ = lo / 64;
  words_.assign(size_t(hi / 64 - first_word_ + 1), 0);
}

void ActiveTags::activate(uint32_t node) {
  const uint64_t w = node / 64;
  if (words_.empty()) first_word_ = w;
  if (w < first_word_) {  // only a resume sets nodes left of the window
    words_.insert(words_.begin(), size_t(first_word_ - w), 0);
    first_word_ = w;
  }
  if (w >= first_word_ + words_.size()) {
    // Grow by an eighth, not by doubling: the bits held stay within ~12 % of the window (amortized O(1)).
    const size_t size = size_t(w - first_word_ + 1);
    if (size > words_.capacity()) words_.reserve(std::max(size, words_.capacity() + words_.capacity() / 8 + 8));
    words_.resize(size, 0);
  }
  uint64_t& word = words_[w - first_word_];
  const uint64_t bit = uint64_t(1) << (node % 64);
  active_ += (word & bit) == 0;
  word |= bit;
}

void ActiveTags::deactivate(uint32_t node) {
  if (!is_active(node)) return;
  uint64_t& word = words_[node / 64 - first_word_];
  word &= ~(uint64_t(1) << (node % 64));
  --active_;
  if (word == 0) drop_leading_zero_words();
}

void ActiveTags::drop_leading_zero_words() {
  size_t zeros = 0;
  while (zeros < words_.size() && words_[zeros] == 0) ++zeros;
  // Erasing shifts the window: wait until the dead prefix is worth it (amortized O(1) per word).
  if (zeros == 0 || (zeros < words_.size() && zeros * 8 < words_.size())) return;
  words_.erase(words_.begin(), words_.begin() + ptrdiff_t(zeros));
  first_word_ += zeros;
  if (words_.empty()) first_word_ = 0;
  // Give memory back once the window is well under what is held (amortized: halving).
  if (words_.capacity() > 64 && words_.size() < words_.capacity() / 4) words_.shrink_to_fit();
}

uint32_t ActiveTags::next_active(uint32_t from) const {
  uint64_t w = std::max<uint64_t>(from / 64, first_word_);
  if (w >= first_word_ + words_.size()) return UINT32_MAX;
  uint64_t word = words_[w - first_word_];
  if (w == from / 64) word &= ~uint64_t(0) << (from % 64);
  for (;;) {
    if (word) return uint32_t(w * 64 + uint64_t(std::countr_zero(word)));
    if (++w >= first_word_ + words_.size()) return UINT32_MAX;
    word = words_[w - first_word_];
  }
}

uint32_t ActiveTags::win_min() const { return next_active(0); }

uint32_t ActiveTags::win_max() const {
  for (size_t i = words_.size(); i-- > 0;)
    if (words_[i]) return uint32_t((first_word_ + i) * 64 + 63 - uint64_t(std::countl_zero(words_[i])));
  return 0;
}

}  // namespace pms
