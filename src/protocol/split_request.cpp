// The receiver-driven request code (cheng-ooi 2008 §4.3, Algorithm 1; docs/protocol.md, "Split request
// code"). Bits are written MSB first, so the code reads like the paper's bit strings ('1011001000').
#include <algorithm>
#include <bit>
#include <string>

#include "common/error.h"
#include "protocol/message_types.h"
#include "protocol/split_request.h"
#include "spm/vertex_id.h"

namespace pms::protocol {
namespace {

constexpr unsigned kMaxGolombZeros = 32;  // values below 2^32: every field is a u32

class BitWriter {
 public:
  void bit(bool b) {
    if (fill_ == 0) out_.push_back(0);
    if (b) out_.back() |= uint8_t(0x80u >> fill_);
    fill_ = (fill_ + 1) % 8;
  }
  // Exp-Golomb of order 0: n zeros, then value + 1 in its n + 1 bits.
  void golomb(uint64_t value) {
    const uint64_t v = value + 1;
    const int n = 63 - std::countl_zero(v);
    for (int i = 0; i < n; ++i) bit(false);
    for (int i = n; i >= 0; --i) bit((v >> i) & 1);
  }
  std::vector<uint8_t> take() { return std::move(out_); }

 private:
  std::vector<uint8_t> out_;
  unsigned fill_ = 0;
};

class BitReader {
 public:
  explicit BitReader(std::span<const uint8_t> data) : data_(data) {}
  bool bit(const char* field) {
    if (pos_ >= 8 * data_.size()) fail(ErrorCode::bad_message, field, "the code is truncated");
    const bool b = (data_[pos_ / 8] >> (7 - pos_ % 8)) & 1;
    ++pos_;
    return b;
  }
  uint64_t golomb(const char* field) {
    unsigned zeros = 0;
    while (!bit(field))
      if (++zeros > kMaxGolombZeros) fail(ErrorCode::bad_message, field, "an Exp-Golomb value over 32 bits");
    uint64_t v = 1;
    for (unsigned i = 0; i < zeros; ++i) v = v << 1 | uint64_t(bit(field));
    return v - 1;
  }
  // The one canonical encoding: zero padding to the byte boundary and nothing after it.
  void expect_end() {
    if ((pos_ + 7) / 8 != data_.size()) fail(ErrorCode::bad_message, "end", "bytes after the end of the code");
    while (pos_ % 8)
      if (bit("padding")) fail(ErrorCode::bad_message, "padding", "non-zero padding bits");
  }
  [[noreturn]] void fail(ErrorCode code, const char* field, const std::string& what) const {
    throw ProtocolError(code, std::string("split request: ") + field + " (bit " + std::to_string(pos_) + "): " + what);
  }

 private:
  std::span<const uint8_t> data_;
  size_t pos_ = 0;
};

// Pre-order key: the path below the root left-aligned in 63 bits (the leading 1 at bit 63).
uint64_t path_key(VertexId v) { return v.node << (63 - v.depth()); }

// Which child of the node at `depth` on v's path leads towards v (v strictly below it).
int branch(VertexId v, int depth) { return int(v.node >> (v.depth() - depth - 1)) & 1; }

// Algorithm 1 over ids[lo, hi), all in the subtree of `node` (at `depth`) and none an ancestor of another.
void encode_subtree(BitWriter& w, const std::vector<VertexId>& ids, size_t lo, size_t hi, uint64_t node, int depth) {
  if (hi - lo == 1 && ids[lo].node == node) {  // a requested node: neither subtree is entered
    w.bit(false);
    w.bit(false);
    return;
  }
  size_t mid = lo;
  while (mid < hi && branch(ids[mid], depth) == 0) ++mid;
  w.bit(mid > lo);
  if (mid > lo) encode_subtree(w, ids, lo, mid, node << 1, depth + 1);
  w.bit(hi > mid);
  if (hi > mid) encode_subtree(w, ids, mid, hi, node << 1 | 1, depth + 1);
}

struct TreeDecoder {
  BitReader& r;
  const SplitRequestLimits& limits;
  std::vector<VertexId>& ids;
  uint32_t tree;

  void subtree(uint64_t node, int depth) {
    const bool left = r.bit("subtree code");
    if (left) descend(node << 1, depth + 1);
    const bool right = r.bit("subtree code");
    if (right) descend(node << 1 | 1, depth + 1);
    if (left || right) return;
    if (depth > limits.max_node_depth)
      r.fail(ErrorCode::bad_id, "subtree code",
             "tree " + std::to_string(tree) + " has no split at depth " + std::to_string(depth));
    if (ids.size() >= limits.max_ids)
      r.fail(ErrorCode::too_large, "subtree code", "more than " + std::to_string(limits.max_ids) + " ids");
    ids.push_back({tree, node});
  }
  void descend(uint64_t child, int depth) {
    if (depth > limits.max_node_depth)
      r.fail(ErrorCode::bad_id, "subtree code",
             "tree " + std::to_string(tree) + " has no split at depth " + std::to_string(depth) +
                 " (the model's deepest split is at " + std::to_string(limits.max_node_depth) + ")");
    subtree(child, depth);
  }
};

}  // namespace

bool code_order(VertexId a, VertexId b) {
  if (a.tree != b.tree) return a.tree < b.tree;
  if (path_key(a) != path_key(b)) return path_key(a) < path_key(b);
  return a.node < b.node;  // an ancestor before its descendants
}

std::vector<uint8_t> encode_split_request(const SplitRequest& request) {
  std::vector<VertexId> ids = request.ids;
  if (ids.empty()) fail("split request", "no ids to request");
  for (VertexId v : ids)
    if (!is_vertex(v)) fail("split request", "node id 0 is not a vertex");
  std::sort(ids.begin(), ids.end(), code_order);
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  // In pre-order an ancestor's subtree follows it at once: neighbours suffice.
  for (size_t i = 1; i < ids.size(); ++i)
    if (is_ancestor_or_self(ids[i - 1], ids[i]))
      fail("split request", to_string(ids[i - 1]) + " is an ancestor of " + to_string(ids[i]));
  BitWriter w;
  w.golomb(request.depth);
  size_t trees = 0;
  for (size_t i = 0; i < ids.size(); ++i) trees += i == 0 || ids[i].tree != ids[i - 1].tree;
  w.golomb(trees - 1);
  for (size_t lo = 0, previous = 0; lo < ids.size();) {
    size_t hi = lo;
    while (hi < ids.size() && ids[hi].tree == ids[lo].tree) ++hi;
    w.golomb(lo == 0 ? ids[lo].tree : ids[lo].tree - previous - 1);
    previous = ids[lo].tree;
    encode_subtree(w, ids, lo, hi, 1, 0);
    lo = hi;
  }
  return w.take();
}

SplitRequest decode_split_request(std::span<const uint8_t> code, const SplitRequestLimits& limits) {
  BitReader r(code);
  if (code.size() > limits.max_bytes)
    r.fail(ErrorCode::too_large, "code",
           std::to_string(code.size()) + " bytes, over the limit of " + std::to_string(limits.max_bytes));
  SplitRequest request;
  const uint64_t depth = r.golomb("depth");
  if (depth > limits.max_depth)
    r.fail(ErrorCode::bad_message, "depth",
           std::to_string(depth) + " levels, over the limit of " + std::to_string(limits.max_depth));
  request.depth = uint32_t(depth);
  request.ids.reserve(std::min<size_t>(limits.max_ids, 4 * code.size()));  // an id takes 2 bits or more
  const uint64_t trees = r.golomb("tree count") + 1;
  if (trees > limits.max_ids) r.fail(ErrorCode::too_large, "tree count", std::to_string(trees) + " trees");
  uint64_t tree = 0;
  for (uint64_t t = 0; t < trees; ++t) {
    tree = t == 0 ? r.golomb("tree id") : tree + 1 + r.golomb("tree id delta");
    if (tree >= limits.root_count)
      r.fail(ErrorCode::bad_id, "tree id",
             "tree " + std::to_string(tree) + " of a model with " + std::to_string(limits.root_count) + " trees");
    TreeDecoder{r, limits, request.ids, uint32_t(tree)}.subtree(1, 0);
  }
  r.expect_end();
  return request;
}

}  // namespace pms::protocol
