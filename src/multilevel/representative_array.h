// The multilevel mesh's representatives, one per vertex, in as few bytes as the vertex count allows: 3
// while every index and the "none" mark fit in 24 bits, else 4. With collapses nearly every vertex has one,
// so this is what keeps the structure within 1.1x the plain indexed mesh (docs/internals.md, "Memory" under
// "Progressive multilevel meshes"): 12n + 12t + 3n against 12n + 12t. A read is one unaligned 4-byte load and a mask
// (one byte of padding at the end keeps the last load inside the array).
#pragma once
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <initializer_list>
#include <utility>
#include <vector>

namespace pms {

class RepresentativeArray {
 public:
  static constexpr uint32_t kNone = 0xFFFFFFFFu;
  static constexpr uint32_t kNarrowNone = 0xFFFFFFu;  // "none" in 3 bytes

  RepresentativeArray() = default;
  RepresentativeArray(std::initializer_list<uint32_t> values) { assign_values(values.begin(), values.size()); }
  explicit RepresentativeArray(const std::vector<uint32_t>& values) { assign_values(values.data(), values.size()); }

  void assign(size_t n, uint32_t value) {
    size_ = n;
    width_ = n < kNarrowNone ? 3 : 4;
    bytes_.assign(width_ * n + 1, 0);
    for (size_t v = 0; v < n; ++v) set(v, value);
  }
  size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  unsigned width() const { return width_; }
  size_t bytes() const { return width_ * size_; }  // the padding byte aside

  uint32_t operator[](size_t v) const {
    uint32_t x;
    std::memcpy(&x, bytes_.data() + width_ * v, 4);
    if (width_ == 4) return x;
    x &= kNarrowNone;
    return x == kNarrowNone ? kNone : x;
  }
  void set(size_t v, uint32_t r) {
    const uint32_t x = width_ == 3 && r == kNone ? kNarrowNone : r;
    std::memcpy(bytes_.data() + width_ * v, &x, width_);  // little-endian: the low 3 bytes first
  }

  // A read-only view of one width, so that a hot loop decides the width once (visit) instead of per read.
  template <unsigned Width>
  struct Reader {
    const uint8_t* bytes;
    uint32_t operator[](size_t v) const {
      uint32_t x;
      std::memcpy(&x, bytes + Width * v, 4);
      if constexpr (Width == 4) return x;
      x &= kNarrowNone;
      return x == kNarrowNone ? kNone : x;
    }
  };
  template <class Fn>
  decltype(auto) visit(Fn&& fn) const {
    return width_ == 3 ? fn(Reader<3>{bytes_.data()}) : fn(Reader<4>{bytes_.data()});
  }

  // `array[v] = r` for a writable array.
  class Reference {
   public:
    Reference(RepresentativeArray& array, size_t v) : array_(array), v_(v) {}
    operator uint32_t() const { return std::as_const(array_)[v_]; }
    Reference& operator=(uint32_t r) {
      array_.set(v_, r);
      return *this;
    }

   private:
    RepresentativeArray& array_;
    size_t v_;
  };
  Reference operator[](size_t v) { return Reference(*this, v); }

  std::vector<uint32_t> values() const {
    std::vector<uint32_t> out(size_);
    for (size_t v = 0; v < size_; ++v) out[v] = (*this)[v];
    return out;
  }
  friend bool operator==(const RepresentativeArray& a, const RepresentativeArray& b) {
    return a.values() == b.values();
  }
  friend bool operator==(const RepresentativeArray& a, const std::vector<uint32_t>& b) { return a.values() == b; }

 private:
  void assign_values(const uint32_t* values, size_t n) {
    assign(n, kNone);
    for (size_t v = 0; v < n; ++v) set(v, values[v]);
  }

  std::vector<uint8_t> bytes_ = std::vector<uint8_t>(1, 0);
  size_t size_ = 0;
  unsigned width_ = 3;
};

}  // namespace pms
