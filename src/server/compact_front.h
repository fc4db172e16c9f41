// A sender-driven session's front between VIEWs, in about two bits per front node (issue 45; the DAG
// mode's CompactDagCut codes its cut the same way): the split set as the hierarchy's shape, breadth first.
// The front only moves down (a split sent is never taken back), so the split set is a top part of each
// tree and the front is its boundary. While a session answers a VIEW it works on windowed active tags
// (active_tags.h), decoded from this code when the answer starts and coded back when it ends: an idle
// session, which is most of a real fleet, holds only the code.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "server/active_tags.h"
#include "spm/hierarchy.h"

namespace pms {

// The code: a bit per root (split?), then, breadth first over the split nodes, a bit per child (split?),
// and the tags' window (the lowest and highest active node), so that decoding sizes it once: the walk meets
// a level's nodes in its parents' order, which is not their index order (a level is packed largest
// deviation first, build.cpp).
class CompactFront {
 public:
  CompactFront() = default;  // no front: a session that has not opened
  // The front of `tags`, which must be a front of the whole forest of `model` (every root-to-leaf path
  // crosses it once); std::logic_error otherwise (the server's fault, not the peer's).
  CompactFront(const ModelData& model, const ActiveTags& tags);

  // The tags of this front, in a window sized once.
  ActiveTags tags(const ModelData& model) const;

  size_t active_count() const { return active_; }
  uint64_t code_bits() const { return bits_; }
  size_t memory_bytes() const { return words_.capacity() * sizeof(uint64_t); }
  bool empty() const { return bits_ == 0; }

 private:
  std::vector<uint64_t> words_;
  uint64_t bits_ = 0;
  size_t active_ = 0;
  uint32_t lowest_ = 0, highest_ = 0;
};

}  // namespace pms
