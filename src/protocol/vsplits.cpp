// VSPLITS: a batch of vsplit packets (kim-lee-kobbelt §5.2, Fig. 3b; Table 2). Per packet the topology
// is only the ids of v_s, v̂_l and v̂_r — v_t and v_u are v_s's children, implied — each written as
//   tree-id (tree_id_bits) | depth (depth_field_bits) | the node-id's path below the root (depth bits),
// i.e. the heap node-id without its implicit leading 1, so an id costs what its depth needs rather than
// the model's worst case. Then v_t's quantized position (v_u keeps v_s's), info_t and info_u (43 or 65
// bits each) and the optional normal / color of v_t (info_t and info_u only when the session's context
// has refinement info: not in a view-independent session). The whole batch is one bit stream padded once at the end:
// packets are not byte-aligned (docs/protocol.md has the measurements that chose this). DAG_OPS (StreamMode::dag) is
// the same packets after a list of collapse ids in the same id code. In a session with split records
// (StreamContext::records) a packet is v_s's id and then the compact split record (spm/split_codec.h) coded
// against what the receiver holds about v_s.
#include <algorithm>
#include <bit>
#include <cmath>
#include <functional>
#include <unordered_map>
#include <utility>

#include "protocol/message_types.h"
#include "protocol/packet_bits.h"
#include "protocol/position_grid.h"
#include "protocol/server_messages.h"
#include "protocol/split_bands.h"
#include "protocol/stream_context.h"
#include "protocol/wire_internal.h"
#include "spm/refine_info.h"
#include "spm/split_record.h"
#include "spm/vertex_id.h"

namespace pms::protocol {
namespace {

constexpr unsigned kCutLeft = 1, kCutRight = 2;  // the 2-bit cut flags
constexpr uint32_t kCutFlagBits = 2;

uint32_t attribute_bits(const StreamContext& c) { return (c.has_normals ? 32 : 0) + (c.has_colors ? 32 : 0); }
// info_t + info_u; a view-independent session's packets have none (its client never runs qrefine).
uint32_t refinement_bits(const SplitRecord& s, const StreamContext& c) {
  return c.has_refinement ? refine_bits(s.info_t) + refine_bits(s.info_u) : 0;
}

// Smallest packet: depth-0 ids, one cut vertex. Bounds a batch's count by its bytes before allocating.
uint64_t min_packet_bits(const StreamContext& c) {
  const uint64_t id = c.tree_id_bits + depth_field_bits(c.node_id_bits);
  if (c.records) return id;  // a record can be 0 bits under degenerate tables
  return 2 * id + kCutFlagBits + 3 * uint64_t(c.grid.bits) + (c.has_refinement ? 2 * kMinRefineBits : 0) +
         attribute_bits(c);
}

}  // namespace

void write_id(Writer& w, VertexId v, const StreamContext& c, const char* field) {
  if (!is_vertex(v) || v.tree >= c.root_count || uint32_t(v.depth()) > c.node_id_bits)
    fail("VSPLITS", std::string(field) + " " + to_string(v) + " is outside the model's ids");
  const int depth = v.depth();
  w.bits(v.tree, c.tree_id_bits);
  w.bits(uint64_t(depth), depth_field_bits(c.node_id_bits));
  w.bits(v.node, unsigned(depth));  // the low `depth` bits: the leading 1 is implied
}

namespace {

VertexId read_id(Reader& r, const StreamContext& c, const char* field) {
  VertexId v;
  v.tree = uint32_t(r.bits(c.tree_id_bits, field));
  if (v.tree >= c.root_count)
    r.fail(ErrorCode::bad_id, field,
           "tree-id " + std::to_string(v.tree) + " >= root count " + std::to_string(c.root_count));
  const uint32_t depth = uint32_t(r.bits(depth_field_bits(c.node_id_bits), field));
  if (depth > c.node_id_bits)
    r.fail(ErrorCode::bad_id, field,
           "depth " + std::to_string(depth) + " > the model's " + std::to_string(c.node_id_bits));
  v.node = (uint64_t(1) << depth) | r.bits(depth, field);
  return v;
}

VertexId read_vs(Reader& r, const StreamContext& c) {
  const VertexId vs = read_id(r, c, "v_s");
  if (uint32_t(vs.depth()) >= c.node_id_bits)
    r.fail(ErrorCode::bad_id, "v_s", to_string(vs) + " is at the deepest level: it has no children to split into");
  return vs;
}

// What the receiver holds about each v_s of a batch of record-coded packets: StreamContext::held for what
// it held before the batch, the batch's own splits for their children (a node's split comes before its
// children's). A node split twice in one batch is refused here: the receiver would refuse the second
// split anyway, and a hostile batch cannot repeat one cheap packet.
class BatchContexts {
 public:
  BatchContexts(const StreamContext& c, size_t packets) : c_(c) { made_.reserve(2 * std::min<size_t>(packets, 4096)); }

  // Empty when v_s has a context (then in `out`); else why it has none.
  std::string find(VertexId vs, SplitContext& out) const {
    const Key key{vs.tree, vs.node};
    if (const auto it = made_.find(key); it != made_.end()) {
      if (it->second.split) return to_string(vs) + " is split a second time in this batch";
      out = it->second.context;
      return "";
    }
    if (c_.held && c_.held(vs, out) && out.vs == vs) return "";
    return to_string(vs) + " is not a vertex the receiver holds";
  }

  // v_s is split: its children are held from now on (v_u keeps v_s's position and attributes: half-edge
  // collapse).
  void split(const SplitContext& s, const SplitPayload& p) {
    made_[Key{s.vs.tree, s.vs.node}].split = true;  // its context is not needed again
    SplitContext t, u;
    t.vs = s.vs.child(0);
    u.vs = s.vs.child(1);
    std::copy_n(p.position_t, 3, t.position_s);
    std::copy_n(s.position_s, 3, u.position_s);
    std::copy_n(p.normal_t, 2, t.normal_s);
    std::copy_n(s.normal_s, 2, u.normal_s);
    std::copy_n(p.color_t, 4, t.color_s);
    std::copy_n(s.color_s, 4, u.color_s);
    t.info_s = p.info_t;
    u.info_s = p.info_u;
    t.ancestor_cuts[0] = u.ancestor_cuts[0] = p.cut_l;
    t.ancestor_cuts[1] = u.ancestor_cuts[1] = p.cut_r;
    std::copy_n(s.ancestor_cuts.begin(), s.ancestor_cuts.size() - 2, t.ancestor_cuts.begin() + 2);
    std::copy_n(s.ancestor_cuts.begin(), s.ancestor_cuts.size() - 2, u.ancestor_cuts.begin() + 2);
    made_[Key{t.vs.tree, t.vs.node}] = {t, false};
    made_[Key{u.vs.tree, u.vs.node}] = {u, false};
  }

 private:
  using Key = std::pair<uint32_t, uint64_t>;
  struct KeyHash {
    size_t operator()(const Key& k) const { return std::hash<uint64_t>()(k.second * 0x9E3779B97F4A7C15ull ^ k.first); }
  };
  struct Made {
    SplitContext context;
    bool split = false;
  };
  const StreamContext& c_;
  std::unordered_map<Key, Made, KeyHash> made_;
};

// v_s's id, then its record (docs/protocol.md, "VSPLITS"): every check of SplitCodec::decode applies.
void read_record_packet(Reader& r, const StreamContext& c, BatchContexts& batch, SplitRecord& s) {
  s.vs = read_vs(r, c);
  SplitContext context;
  if (const std::string why = batch.find(s.vs, context); !why.empty()) r.fail(ErrorCode::bad_id, "v_s", why);
  BitReader bits(r.payload(), r.position(), 8 * uint64_t(r.payload().size()), "record");
  SplitPayload payload;
  try {
    payload = c.records->decode(context, bits);
  } catch (const ProtocolError&) {
    throw;
  } catch (const Error& e) {
    r.fail(ErrorCode::bad_message, "record", e.what());
  }
  r.seek(bits.position());
  s = split_record_of(s.vs, payload, c.grid, *c.records);
  for (float v : s.position_t)
    if (!std::isfinite(v)) r.fail(ErrorCode::bad_message, "position", "is not finite");
  batch.split(context, payload);
}

void write_record_packet(Writer& w, const SplitRecord& s, const StreamContext& c, BatchContexts& batch) {
  if (s.has_normal != c.has_normals || s.has_color != c.has_colors)
    fail("VSPLITS", "split of " + to_string(s.vs) + ": normal/color presence differs from the model's");
  if (uint32_t(s.vs.depth()) >= c.node_id_bits)
    fail("VSPLITS", "split of " + to_string(s.vs) + ": its children would be deeper than node_id_bits");
  SplitContext context;
  if (const std::string why = batch.find(s.vs, context); !why.empty()) fail("VSPLITS", "split of " + why);
  SplitPayload payload;
  payload.cut_l = s.cut_l;
  payload.cut_r = s.cut_r;
  quantize_position(c.grid, s.position_t, payload.position_t);
  payload.info_t = as_sent(s.info_t);
  payload.info_u = as_sent(s.info_u);
  if (s.has_normal) encode_normal(s.normal_t, payload.normal_t);
  if (s.has_color) std::copy_n(s.color_t, 4, payload.color_t);
  BitWriter record;
  c.records->encode(context, payload, record);
  write_id(w, s.vs, c, "v_s");
  const std::vector<uint8_t>& bytes = record.bytes();
  for (uint64_t i = 0; i < record.size(); i += 8)
    w.bits(bytes[i / 8], unsigned(std::min<uint64_t>(8, record.size() - i)));
  batch.split(context, payload);
}

void read_packet(Reader& r, const StreamContext& c, SplitRecord& s) {
  s.vs = read_vs(r, c);
  const unsigned cuts = unsigned(r.bits(kCutFlagBits, "cut flags"));
  if (cuts == 0) r.fail(ErrorCode::bad_message, "cut flags", "neither v_l nor v_r is present");
  if (cuts & kCutLeft) s.cut_l = read_id(r, c, "v_l");
  if (cuts & kCutRight) s.cut_r = read_id(r, c, "v_r");
  // A cut vertex is a leaf beside v_s's faces, never inside its own subtree (pms-format.md, CUTL/CUTR).
  if (is_ancestor_or_self(s.vs, s.cut_l))
    r.fail(ErrorCode::bad_id, "v_l", to_string(s.cut_l) + " is inside v_s's subtree");
  if (is_ancestor_or_self(s.vs, s.cut_r))
    r.fail(ErrorCode::bad_id, "v_r", to_string(s.cut_r) + " is inside v_s's subtree");
  uint32_t q[3];
  for (uint32_t& v : q) v = uint32_t(r.bits(c.grid.bits, "position"));
  dequantize_position(c.grid, q, s.position_t);
  for (float v : s.position_t)
    if (!std::isfinite(v)) r.fail(ErrorCode::bad_message, "position", "is not finite");
  if (c.has_refinement) {
    s.info_t = read_refine(r, "info_t");
    s.info_u = read_refine(r, "info_u");
  } else {
    s.info_t = s.info_u = RefineInfo{};  // not on the wire: zeroed
  }
  s.has_normal = c.has_normals;
  if (c.has_normals) {
    const uint16_t n[2] = {r.u16("normal"), r.u16("normal")};
    decode_normal(n, s.normal_t);
  }
  s.has_color = c.has_colors;
  if (c.has_colors)
    for (uint8_t& v : s.color_t) v = r.u8("color");
}

}  // namespace

void write_packet(Writer& w, const SplitRecord& s, const StreamContext& c) {
  if (c.records) fail("VSPLITS", "split records are coded per batch (encode(VSplits))");
  if (s.has_normal != c.has_normals || s.has_color != c.has_colors)
    fail("VSPLITS", "split of " + to_string(s.vs) + ": normal/color presence differs from the model's");
  if (uint32_t(s.vs.depth()) >= c.node_id_bits)
    fail("VSPLITS", "split of " + to_string(s.vs) + ": its children would be deeper than node_id_bits");
  write_id(w, s.vs, c, "v_s");
  const unsigned cuts = (is_vertex(s.cut_l) ? kCutLeft : 0) | (is_vertex(s.cut_r) ? kCutRight : 0);
  if (cuts == 0) fail("VSPLITS", "split of " + to_string(s.vs) + " has no cut vertex");
  w.bits(cuts, kCutFlagBits);
  if (cuts & kCutLeft) write_id(w, s.cut_l, c, "v_l");
  if (cuts & kCutRight) write_id(w, s.cut_r, c, "v_r");
  uint32_t q[3];
  quantize_position(c.grid, s.position_t, q);
  for (uint32_t v : q) w.bits(v, c.grid.bits);
  if (c.has_refinement) {
    write_refine(w, s.info_t, "VSPLITS info_t");
    write_refine(w, s.info_u, "VSPLITS info_u");
  }
  if (c.has_normals) {
    uint16_t n[2];
    encode_normal(s.normal_t, n);
    w.u16(n[0]);
    w.u16(n[1]);
  }
  if (c.has_colors)
    for (uint8_t v : s.color_t) w.u8(v);
}

uint8_t vsplits_flags(bool final, bool ahead) {
  if (final && ahead) fail("VSPLITS", "a batch sent ahead answers no VIEW: it is never final");
  return uint8_t((final ? kFlagFinal : 0) | (ahead ? kFlagAhead : 0));
}

void write_vsplits_header(Writer& w, uint32_t frame, uint8_t flags, size_t count) {
  if (count > UINT32_MAX) fail("VSPLITS", "too many packets in one batch");
  w.u32(frame);
  w.u8(flags);
  w.u32(uint32_t(count));
}

uint32_t depth_field_bits(uint32_t node_id_bits) {
  return node_id_bits == 0 ? 1 : uint32_t(std::bit_width(node_id_bits));
}

uint32_t id_bits(VertexId id, const StreamContext& c) {
  return c.tree_id_bits + depth_field_bits(c.node_id_bits) + uint32_t(id.depth());
}

PacketBits packet_bits(const SplitRecord& s, const StreamContext& c) {
  PacketBits bits;
  bits.topology = id_bits(s.vs, c) + kCutFlagBits;
  if (is_vertex(s.cut_l)) bits.topology += id_bits(s.cut_l, c);
  if (is_vertex(s.cut_r)) bits.topology += id_bits(s.cut_r, c);
  bits.position = 3 * c.grid.bits;
  bits.refinement = refinement_bits(s, c);
  bits.attributes = attribute_bits(c);
  return bits;
}

std::vector<uint8_t> encode(const VSplits& m, const StreamContext& c) {
  if (const std::string why = check_context(c); !why.empty()) fail("VSPLITS", "stream context: " + why);
  if (m.splits.size() > kMaxPacketsPerMessage) fail("VSPLITS", "too many packets in one batch");
  Writer w(MessageType::vsplits);
  w.reserve_payload(9 + m.splits.size() * min_packet_bits(c) / 8);
  write_vsplits_header(w, m.frame, vsplits_flags(m.final, m.ahead), m.splits.size());
  if (c.records) {
    BatchContexts batch(c, m.splits.size());
    for (const SplitRecord& s : m.splits) write_record_packet(w, s, c, batch);
  } else {
    for (const SplitRecord& s : m.splits) write_packet(w, s, c);
  }
  return w.finish();
}

namespace {

// A packet count and its packets, checked against the bytes left before anything is allocated.
std::vector<SplitRecord> read_packets(Reader& r, const StreamContext& c) {
  const uint32_t count = r.u32("packet count");
  r.check_count(count, min_packet_bits(c), "packet count");
  if (count > kMaxPacketsPerMessage)
    r.fail(ErrorCode::too_large, "packet count", std::to_string(count) + " > " + std::to_string(kMaxPacketsPerMessage));
  std::vector<SplitRecord> splits;
  if (c.records) {
    // A record has no smallest size: the vector grows with the packets that decode, not with the count.
    splits.reserve(std::min<uint32_t>(count, 4096));
    BatchContexts batch(c, count);
    for (uint32_t i = 0; i < count; ++i) {
      r.set_item("packet", i);
      read_record_packet(r, c, batch, splits.emplace_back());
    }
  } else {
    splits.resize(count);
    for (uint32_t i = 0; i < count; ++i) {
      r.set_item("packet", i);
      read_packet(r, c, splits[i]);
    }
  }
  r.clear_item();
  return splits;
}

// The frame number and the flags byte of VSPLITS and DAG_OPS: whether the batch is its answer's last.
bool read_final_flag(Reader& r) {
  const uint8_t flags = r.u8("flags");
  if (flags & ~kFlagFinal) r.fail(ErrorCode::bad_message, "flags", "unknown bits set");
  return flags & kFlagFinal;
}

}  // namespace

VSplits decode_vsplits(std::span<const uint8_t> payload, const StreamContext& c) {
  Reader r(payload, MessageType::vsplits);
  if (const std::string why = check_context(c); !why.empty()) r.fail(ErrorCode::internal, "stream context", why);
  VSplits m;
  m.frame = r.u32("frame");
  const uint8_t flags = r.u8("flags");
  if (flags & ~(kFlagFinal | kFlagAhead)) r.fail(ErrorCode::bad_message, "flags", "unknown bits set");
  if ((flags & kFlagFinal) && (flags & kFlagAhead)) r.fail(ErrorCode::bad_message, "flags", "final and ahead");
  m.final = flags & kFlagFinal;
  m.ahead = flags & kFlagAhead;
  m.splits = read_packets(r, c);
  r.expect_end();
  return m;
}

std::vector<uint8_t> encode(const DagOps& m, const StreamContext& c) {
  if (const std::string why = check_context(c); !why.empty()) fail("DAG_OPS", "stream context: " + why);
  if (c.records) fail("DAG_OPS", "stream context: DAG_OPS packets are not split records");
  if (m.collapses.size() > UINT32_MAX || m.splits.size() > kMaxPacketsPerMessage)
    fail("DAG_OPS", "too many operations");
  Writer w(MessageType::dag_ops);
  w.reserve_payload(13 + m.splits.size() * min_packet_bits(c) / 8 + m.collapses.size() * 4);
  w.u32(m.frame);
  w.u8(m.final ? kFlagFinal : 0);
  w.u32(uint32_t(m.collapses.size()));
  for (VertexId v : m.collapses) write_id(w, v, c, "collapse");
  w.u32(uint32_t(m.splits.size()));
  for (const SplitRecord& s : m.splits) write_packet(w, s, c);
  return w.finish();
}

DagOps decode_dag_ops(std::span<const uint8_t> payload, const StreamContext& c) {
  Reader r(payload, MessageType::dag_ops);
  if (const std::string why = check_context(c); !why.empty()) r.fail(ErrorCode::internal, "stream context", why);
  if (c.records) r.fail(ErrorCode::internal, "stream context", "DAG_OPS packets are not split records");
  DagOps m;
  m.frame = r.u32("frame");
  m.final = read_final_flag(r);
  const uint32_t collapses = r.u32("collapse count");
  r.check_count(collapses, c.tree_id_bits + depth_field_bits(c.node_id_bits), "collapse count");
  m.collapses.resize(collapses);
  for (uint32_t i = 0; i < collapses; ++i) {
    r.set_item("collapse", i);
    m.collapses[i] = read_id(r, c, "v_s");
  }
  r.clear_item();
  m.splits = read_packets(r, c);
  r.expect_end();
  return m;
}

}  // namespace pms::protocol
