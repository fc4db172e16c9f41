// Which vertex splits can ever wait on another split in selective streaming: one bit per node of a
// model, derived from its hierarchy once and shared by every session that streams it.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "spm/hierarchy.h"

namespace pms {

// Which splits SelStreamVSplit's partial-order check can ever stop (kim-lee-kobbelt §5.3): v_s waits when
// ActiveAncestor(v̂_l) = ActiveAncestor(v̂_r). Both climbs miss the cache at every level of a large model,
// yet the answer is known for most splits from the hierarchy alone. When v̂_l and v̂_r lie in different
// trees, or their deepest common ancestor w is a strict ancestor of v_s, w is split whenever v_s is active,
// so the two active ancestors lie below w on different branches and differ. Only the rest are checked
// (a small share of a scan's splits). One bit per node, built once per model and shared by its sessions.
class DependencyFilter {
 public:
  DependencyFilter() = default;  // nothing known: every split is checked
  explicit DependencyFilter(const ModelData& model);
  bool may_wait(uint32_t node) const { return bits_.empty() || ((bits_[node / 64] >> (node % 64)) & 1); }
  size_t memory_bytes() const { return bits_.capacity() * sizeof(uint64_t); }

 private:
  std::vector<uint64_t> bits_;
};

}  // namespace pms
