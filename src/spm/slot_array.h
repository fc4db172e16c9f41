// Per-slot records of the engine (SelectiveMesh's vertex records, SelectiveRefinement's slots) that
// are never initialised as a whole: memory is written only where a slot is used, so a fresh mesh pays
// for the slots its view reaches, not for the model. Until its owner writes it, a record holds zeros
// or what an earlier array of the same kind left there, and the owner tells the records it wrote from
// those (SelectiveMesh by its active bits, SelectiveRefinement by a stamp of its own). Grows as
// slot_growth.h says: small arrays double on the heap, zeroed; large ones take the whole known range
// at once, a zeroed mapping or a block an array of the same kind freed (its pages still mapped).
#pragma once
#include <cstddef>
#include <cstdlib>
#include <cstring>
#include <new>
#include <type_traits>

#include "common/huge_pages.h"
#include "spm/slot_growth.h"

namespace pms {

// kKind: which arrays may inherit this one's blocks (see take_recycled_block); > 0, one per record type.
template <class T, int kKind>
class SlotArray {
  static_assert(std::is_trivially_copyable_v<T> && std::is_trivially_destructible_v<T> && kKind > 0);

 public:
  SlotArray() = default;
  SlotArray(const SlotArray&) = delete;
  SlotArray& operator=(const SlotArray&) = delete;
  ~SlotArray() { release(data_, bytes_); }

  size_t size() const { return size_; }  // slots [0, size()) may be read and written
  T& operator[](size_t slot) { return data_[slot]; }
  const T& operator[](size_t slot) const { return data_[slot]; }

  // Makes slots [0, end) of `known` usable; the records written so far stay.
  void grow(size_t end, size_t known) {
    if (end <= size_) return;
    const size_t capacity = slot_capacity(end, size_, known, sizeof(T));
    size_t bytes = capacity * sizeof(T);
    void* data = nullptr;
    if (bytes <= kSmallSlotBytes) {
      data = std::aligned_alloc(alignof(T) < 64 ? 64 : alignof(T), bytes);
      if (data) std::memset(data, 0, bytes);
    } else {
      bytes = huge_block_bytes(bytes);
      data = take_recycled_block(bytes, kKind);
      if (!data) data = map_zeroed(bytes);
    }
    if (!data) throw std::bad_alloc();
    if (size_ > 0) std::memcpy(data, data_, size_ * sizeof(T));
    release(data_, bytes_);
    data_ = static_cast<T*>(data);
    bytes_ = bytes;
    size_ = bytes / sizeof(T);
  }

 private:
  static void release(T* data, size_t bytes) {
    if (!data) return;
    if (bytes <= kSmallSlotBytes) std::free(data);
    else recycle_block(data, bytes, kKind);
  }

  T* data_ = nullptr;
  size_t size_ = 0;
  size_t bytes_ = 0;
};

}  // namespace pms
