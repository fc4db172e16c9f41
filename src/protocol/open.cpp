// OPEN{model, mode, optional resume front}. The resume list is the set of leaves of the client's partial
// hierarchy, which is always a complete front of the forest (every root-to-leaf path meets one of them):
// roots arrive with BASE and every split adds both children. A front is coded in preorder, one bit per
// node: 1 = split (both children follow), 0 = a listed leaf, trees in tree-id order. That is 2F - R bits
// for F leaves in R trees — the server's active tags of kim-lee-kobbelt §6.1, rebuilt from the client
// alone (DESIGN.md §9 resume) — instead of a ~40-bit <tree-id, node-id> per leaf.
#include <algorithm>

#include "protocol/wire_internal.h"

namespace pms::protocol {
namespace {

constexpr int kMaxDepth = 63;  // node-ids are 64 bits with the leading 1
constexpr uint8_t kFlagResume = 1;
constexpr uint8_t kFlagViewIndependent = 2;  // StreamMode::view_independent

// Preorder: in the same tree, left-aligned path bits compare like the bit strings they are (for ids
// where neither is an ancestor of the other, which is the case inside a front).
bool preorder_less(VertexId a, VertexId b) {
  if (a.tree != b.tree) return a.tree < b.tree;
  return a.node << (63 - a.depth()) < b.node << (63 - b.depth());
}

struct FrontWriter {
  Writer& w;
  const std::vector<VertexId>& leaves;  // sorted in preorder
  size_t next = 0;

  void subtree(VertexId node) {
    if (next < leaves.size() && leaves[next] == node) {
      w.bits(0, 1);
      ++next;
      return;
    }
    if (next >= leaves.size() || !is_ancestor_or_self(node, leaves[next]))
      fail("OPEN", "resume: no leaf listed under " + to_string(node) + ": the list is not a complete front");
    w.bits(1, 1);  // node.depth() < 63 here: a listed descendant exists
    subtree(node.child(0));
    subtree(node.child(1));
  }
};

struct FrontReader {
  Reader& r;
  uint64_t max_leaves;
  std::vector<VertexId>& leaves;

  void subtree(VertexId node) {
    if (r.bits(1, "resume") == 0) {
      if (leaves.size() >= max_leaves)
        r.fail(ErrorCode::too_large, "resume", "more than " + std::to_string(max_leaves) + " leaves");
      leaves.push_back(node);
      return;
    }
    if (node.depth() >= kMaxDepth) r.fail(ErrorCode::bad_id, "resume", "a split below depth 63");
    subtree(node.child(0));
    subtree(node.child(1));
  }
};

}  // namespace

std::vector<uint8_t> encode(const Open& m) {
  Writer w(MessageType::open);
  w.string(m.model, kMaxNameBytes, "model");
  const bool vi = m.mode == StreamMode::view_independent;
  if (!vi && m.mode != StreamMode::sender_driven) fail("OPEN", "mode: not a mode this protocol knows");
  w.u8(uint8_t((m.resume.empty() ? 0 : kFlagResume) | (vi ? kFlagViewIndependent : 0)));
  if (!m.resume.empty()) {
    std::vector<VertexId> leaves = m.resume;
    for (VertexId v : leaves)
      if (!is_vertex(v) || v.depth() > kMaxDepth) fail("OPEN", "resume: " + to_string(v) + " is not a vertex id");
    std::sort(leaves.begin(), leaves.end(), preorder_less);
    const uint32_t trees = leaves.back().tree + 1;
    w.u32(trees);
    FrontWriter front{w, leaves};
    for (uint32_t t = 0; t < trees; ++t) front.subtree({t, 1});
    if (front.next != leaves.size())  // a duplicate, or an id inside another listed leaf's subtree
      fail("OPEN", "resume: " + to_string(leaves[front.next]) + " is listed twice or below another leaf");
  }
  return w.finish();
}

Open decode_open(std::span<const uint8_t> payload, uint64_t max_resume_leaves) {
  Reader r(payload, MessageType::open);
  Open m;
  m.model = r.string(kMaxNameBytes, "model");
  const uint8_t flags = r.u8("flags");
  if (flags & ~(kFlagResume | kFlagViewIndependent)) r.fail(ErrorCode::bad_message, "flags", "unknown bits set");
  if (flags & kFlagViewIndependent) m.mode = StreamMode::view_independent;
  if (flags & kFlagResume) {
    const uint32_t trees = r.u32("resume tree count");
    if (trees == 0) r.fail(ErrorCode::bad_message, "resume tree count", "is 0");
    r.check_count(trees, 1, "resume tree count");  // each tree takes at least one bit
    FrontReader front{r, max_resume_leaves, m.resume};
    for (uint32_t t = 0; t < trees; ++t) front.subtree({t, 1});
  }
  r.expect_end();
  return m;
}

}  // namespace pms::protocol
