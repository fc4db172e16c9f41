// The leaves of the partial vertex hierarchy a client holds, as a bit per node of the model the server
// serves (UpdateVHierarchy, kim-lee-kobbelt §5.3, on leaves only): what a load client keeps instead of a
// VertexHierarchy, so it can check that no split arrives twice or out of order, resume on what it holds,
// and tell which of its leaves a view wants split.
#pragma once
#include <bit>
#include <cstdint>
#include <vector>

#include "spm/hierarchy.h"
#include "spm/vertex_id.h"

namespace pms::client {

class HeldLeaves {
 public:
  explicit HeldLeaves(const ModelData& model);  // the roots: a session's base mesh

  void hold_roots();
  // v_s stops being a leaf, its children become ones. Throws pms::Error ("server: ...") for a split the
  // model cannot make or of a node that is not a held leaf (sent before, or its parent never was).
  // Returns v_s's node.
  uint32_t split(VertexId vs);
  bool holds(uint32_t node) const { return (bits_[node / 64] >> (node % 64)) & 1; }
  uint64_t splits() const { return splits_; }  // since the roots
  std::vector<VertexId> leaves() const;

  // Calls f(node) for every held leaf, in node order.
  template <class F>
  void for_each_leaf(F&& f) const {
    for (size_t word = 0; word < bits_.size(); ++word)
      for (uint64_t bits = bits_[word]; bits; bits &= bits - 1) f(uint32_t(word * 64 + size_t(std::countr_zero(bits))));
  }
  // True as soon as f(node) is true for a held leaf.
  template <class F>
  bool any_leaf(F&& f) const {
    for (size_t word = 0; word < bits_.size(); ++word)
      for (uint64_t bits = bits_[word]; bits; bits &= bits - 1)
        if (f(uint32_t(word * 64 + size_t(std::countr_zero(bits))))) return true;
    return false;
  }

 private:
  const ModelData* model_;
  std::vector<uint64_t> bits_;  // per model node: a leaf of the partial hierarchy held
  uint64_t splits_ = 0;
};

}  // namespace pms::client
