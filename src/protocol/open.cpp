// OPEN{model, mode, optional resume front}. The resume list is the set of leaves of the client's partial
// hierarchy, which is always a complete front of the forest (every root-to-leaf path meets one of them):
// roots arrive with BASE and every split adds both children. A front is coded in preorder, one bit per
// node: 1 = split (both children follow), 0 = a listed leaf, trees in tree-id order. That is 2F - R bits
// for F leaves in R trees — the server's active tags of kim-lee-kobbelt §6.1, rebuilt from the client
// alone (docs/architecture.md, "Scale-out": resume) — instead of a ~40-bit <tree-id, node-id> per leaf.
#include <algorithm>

#include "protocol/client_messages.h"
#include "protocol/message_types.h"
#include "protocol/wire_internal.h"
#include "spm/vertex_id.h"

namespace pms::protocol {
namespace {

constexpr int kMaxDepth = 63;  // node-ids are 64 bits with the leading 1
constexpr uint8_t kFlagResume = 1;
constexpr uint8_t kFlagViewIndependent = 2;  // StreamMode::view_independent
// StreamMode::sender_plain: an option of the sender-driven mode (actual cut vertices, no refinement info).
constexpr uint8_t kFlagPlain = 4;
constexpr uint8_t kFlagDag = 8;  // StreamMode::dag

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

}  // namespace

std::vector<uint8_t> encode(const Open& m) {
  Writer w(MessageType::open);
  w.string(m.model, kMaxNameBytes, "model");
  const bool vi = m.mode == StreamMode::view_independent, plain = m.mode == StreamMode::sender_plain,
             dag = m.mode == StreamMode::dag;
  if (!vi && !plain && !dag && m.mode != StreamMode::sender_driven)
    fail("OPEN", "mode: not a mode this protocol knows");
  w.u8(uint8_t((m.resume.empty() ? 0 : kFlagResume) | (vi ? kFlagViewIndependent : 0) | (plain ? kFlagPlain : 0) |
               (dag ? kFlagDag : 0)));
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

OpenHeader decode_open_header(std::span<const uint8_t> payload) {
  Reader r(payload, MessageType::open);
  OpenHeader m;
  m.model = r.string(kMaxNameBytes, "model");
  const uint8_t flags = r.u8("flags");
  if (flags & ~(kFlagResume | kFlagViewIndependent | kFlagPlain | kFlagDag))
    r.fail(ErrorCode::bad_message, "flags", "unknown bits set");
  if ((flags & kFlagDag) && (flags & (kFlagViewIndependent | kFlagPlain)))
    r.fail(ErrorCode::bad_message, "flags", "the DAG mode takes neither the view-independent nor the plain bit");
  if ((flags & kFlagViewIndependent) && (flags & kFlagPlain))
    r.fail(ErrorCode::bad_message, "flags", "plain is an option of the sender-driven mode, not of view-independent");
  if (flags & kFlagViewIndependent) m.mode = StreamMode::view_independent;
  if (flags & kFlagPlain) m.mode = StreamMode::sender_plain;
  if (flags & kFlagDag) m.mode = StreamMode::dag;
  if (flags & kFlagResume) {
    m.resume = true;
    m.resume_trees = r.u32("resume tree count");
    if (m.resume_trees == 0) r.fail(ErrorCode::bad_message, "resume tree count", "is 0");
    r.check_count(m.resume_trees, 1, "resume tree count");  // each tree takes at least one bit
  } else {
    r.expect_end();
  }
  m.front_bit = r.position();
  return m;
}

FrontDecoder::FrontDecoder(std::span<const uint8_t> payload, const OpenHeader& header, uint64_t max_leaves)
    : payload_(payload),
      bit_(header.front_bit),
      trees_(header.resume ? header.resume_trees : 0),
      max_leaves_(max_leaves) {
  stack_.reserve(kMaxDepth + 1);
  done_ = trees_ == 0;
}

bool FrontDecoder::next(size_t max_leaves, std::vector<VertexId>& out) {
  if (done_) return true;
  Reader r(payload_, MessageType::open, bit_);
  for (size_t taken = 0; taken < max_leaves;) {
    if (stack_.empty()) {
      if (tree_ == trees_) {
        r.expect_end();
        done_ = true;
        break;
      }
      stack_.push_back({tree_++, 1});
    }
    const VertexId node = stack_.back();
    stack_.pop_back();
    if (r.bits(1, "resume") == 0) {
      if (leaves_ >= max_leaves_)
        r.fail(ErrorCode::too_large, "resume", "more than " + std::to_string(max_leaves_) + " leaves");
      ++leaves_;
      ++taken;
      out.push_back(node);
      continue;
    }
    if (node.depth() >= kMaxDepth) r.fail(ErrorCode::bad_id, "resume", "a split below depth 63");
    stack_.push_back(node.child(1));  // preorder: the left subtree first
    stack_.push_back(node.child(0));
  }
  bit_ = r.position();
  return done_;
}

Open decode_open(std::span<const uint8_t> payload, uint64_t max_resume_leaves) {
  const OpenHeader header = decode_open_header(payload);
  Open m{header.model, {}, header.mode};
  FrontDecoder front(payload, header, max_resume_leaves);
  while (!front.next(SIZE_MAX, m.resume)) {
  }
  return m;
}

}  // namespace pms::protocol
