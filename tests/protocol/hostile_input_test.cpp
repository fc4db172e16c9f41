// Hostile input: every decoder rejects truncated, over-long and garbage payloads with a ProtocolError
// that names the message and the field, and never allocates what a count merely claims.
#include <gtest/gtest.h>
#include <cmath>
#include <cstring>
#include <functional>

#include "protocol/client_messages.h"
#include "protocol/message_types.h"
#include "protocol/model_messages.h"
#include "protocol/server_messages.h"
#include "protocol/stream_context.h"
#include "protocol/wire_internal.h"
#include "protocol_fixtures.h"
#include "spm/split_record.h"
#include "spm/vertex_id.h"

namespace pms::protocol {
namespace {

using test::expect_rejected;
using test::payload_of;
using Payload = std::vector<uint8_t>;

struct Sample {
  MessageType type;
  std::vector<uint8_t> frame;
  std::function<void(std::span<const uint8_t>)> decode;
};

StreamContext small_context() {
  StreamContext c;
  c.root_count = 10;
  c.tree_id_bits = 4;
  c.node_id_bits = 5;  // depth field: 3 bits
  c.grid.bits = 8;
  for (int i = 0; i < 3; ++i) c.grid.max[i] = 1;
  return c;
}

// One valid message of every type (random content from a fixed seed).
std::vector<Sample> samples() {
  test::Rng rng(11);
  const StreamContext c = small_context();
  VSplits batch{3, true, {}};
  for (int i = 0; i < 20; ++i) batch.splits.push_back(test::random_split(rng, c));
  const test::BuiltModel& sphere = test::sphere_model();
  const Base base = make_base(sphere.model(), "sphere");
  View view;
  view.frame = 9;
  return {
      {MessageType::hello, encode(Hello{kProtocolVersion, "me"}), [](auto p) { decode_hello(p); }},
      {MessageType::list, encode(List{}), [](auto p) { decode_list(p); }},
      {MessageType::open, encode(Open{"m", test::random_front(rng, 5, 10)}), [](auto p) { decode_open(p); }},
      {MessageType::view, encode(view), [](auto p) { decode_view(p); }},
      {MessageType::close, encode(Close{}), [](auto p) { decode_close(p); }},
      {MessageType::dag_view, encode(DagView{}), [](auto p) { decode_dag_view(p); }},
      {MessageType::ahead, encode(Ahead{view}), [](auto p) { decode_ahead(p); }},
      {MessageType::hello_ok, encode(HelloOk{kProtocolVersion, "srv", 1000, 2000}), [](auto p) { decode_hello_ok(p); }},
      {MessageType::catalogue, encode(Catalogue{{model_info(sphere.model(), "sphere"), ModelInfo{}}}),
       [](auto p) { decode_catalogue(p); }},
      {MessageType::base, encode(base), [](auto p) { decode_base(p); }},
      {MessageType::vsplits, encode(batch, c), [c](auto p) { decode_vsplits(p, c); }},
      {MessageType::error, encode(ErrorMessage{ErrorCode::bad_id, "no"}), [](auto p) { decode_error(p); }},
  };
}

TEST(HostileInput, EveryTruncationIsRejected) {
  for (const Sample& s : samples()) {
    const Payload payload = payload_of(s.frame, s.type);
    ASSERT_NO_THROW(s.decode(payload)) << to_string(s.type);
    for (size_t size = 0; size < payload.size(); ++size) {
      const Payload cut(payload.begin(), payload.begin() + size);
      expect_rejected([&] { s.decode(cut); }, ErrorCode::bad_message, to_string(s.type) + ": ");
    }
  }
}

TEST(HostileInput, TrailingBytesAreRejected) {
  for (const Sample& s : samples()) {
    Payload payload = payload_of(s.frame, s.type);
    payload.push_back(0);
    expect_rejected([&] { s.decode(payload); }, ErrorCode::bad_message, "trailing bytes");
  }
}

TEST(HostileInput, GarbageAndBitFlipsNeverEscapeAsOtherErrors) {
  test::Rng rng(5);
  for (const Sample& s : samples()) {
    const Payload payload = payload_of(s.frame, s.type);
    for (int trial = 0; trial < 3000; ++trial) {
      Payload bytes;
      if (trial % 2 == 0) {  // random bytes of a random size
        bytes.resize(rng() % 200);
        for (uint8_t& b : bytes) b = uint8_t(rng());
      } else {  // the valid payload with a few bits flipped
        bytes = payload;
        if (bytes.empty()) continue;
        for (int flips = 1 + int(rng() % 3); flips > 0; --flips)
          bytes[rng() % bytes.size()] ^= uint8_t(1u << (rng() % 8));
      }
      try {
        s.decode(bytes);
      } catch (const ProtocolError&) {
      }  // anything else (std::bad_alloc, std::length_error, a crash) fails the test
    }
  }
}

TEST(HostileInput, HelloAndStrings) {
  Payload p = payload_of(encode(Hello{1, "x"}), MessageType::hello);
  p[0] = 'X';
  expect_rejected([&] { decode_hello(p); }, ErrorCode::bad_message, "HELLO: magic: is not PMST");

  Writer w(MessageType::hello);
  for (char c : kMagic) w.u8(uint8_t(c));
  w.u16(1);
  w.u16(2000);  // a name length over kMaxNameBytes; the bytes are not even there
  p = payload_of(w.finish(), MessageType::hello);
  expect_rejected([&] { decode_hello(p); }, ErrorCode::bad_message, "HELLO: client name: 2000 bytes, at most 1024");

  EXPECT_THROW(encode(Hello{1, std::string(kMaxNameBytes + 1, 'a')}), Error);
}

TEST(HostileInput, ViewFields) {
  const Payload good = payload_of(encode(View{}), MessageType::view);
  auto with_f32 = [&](size_t offset, float v) {
    Payload p = good;
    std::memcpy(&p[offset], &v, 4);
    return p;
  };
  auto with_u32 = [&](size_t offset, uint32_t v) {
    Payload p = good;
    std::memcpy(&p[offset], &v, 4);
    return p;
  };
  // Offsets: eye 0, target 12, up 24, fovy 36, width 40, height 44, tolerance 48, frame 52.
  expect_rejected([&] { decode_view(with_f32(4, NAN)); }, ErrorCode::bad_message, "VIEW: eye: is not finite");
  expect_rejected([&] { decode_view(with_f32(28, INFINITY)); }, ErrorCode::bad_message, "VIEW: up: is not finite");
  expect_rejected([&] { decode_view(with_f32(36, 180)); }, ErrorCode::bad_message, "VIEW: camera: fovy_deg");
  expect_rejected([&] { decode_view(with_u32(40, 0)); }, ErrorCode::bad_message, "VIEW: viewport");
  expect_rejected([&] { decode_view(with_u32(44, 100000)); }, ErrorCode::bad_message, "VIEW: viewport");
  expect_rejected([&] { decode_view(with_f32(48, -1)); }, ErrorCode::bad_message, "VIEW: tolerance: is negative");
  View same_points;
  std::copy_n(same_points.camera.target, 3, same_points.camera.eye);
  expect_rejected([&] { decode_view(payload_of(encode(same_points), MessageType::view)); }, ErrorCode::bad_message,
                  "eye and target must differ");
}

TEST(HostileInput, DagViewFields) {
  DagView budget;
  budget.management = DagMode::budget;
  budget.budget = 60000;
  const Payload good = payload_of(encode(budget), MessageType::dag_view);
  const DagView back = decode_dag_view(good);
  EXPECT_EQ(back.max_ops, 300u);
  EXPECT_EQ(back.management, DagMode::budget);
  EXPECT_EQ(back.budget, 60000u);
  // Offsets: the view's 56 bytes, max ops 56, traversal 60, management 61, budget 62.
  auto with = [&](size_t offset, uint64_t v, size_t bytes) {
    Payload p = good;
    std::memcpy(&p[offset], &v, bytes);
    return p;
  };
  expect_rejected([&] { decode_dag_view(with(56, 0, 4)); }, ErrorCode::bad_message, "DAG_VIEW: max ops");
  expect_rejected([&] { decode_dag_view(with(56, kMaxDagOps + 1, 4)); }, ErrorCode::bad_message, "DAG_VIEW: max ops");
  expect_rejected([&] { decode_dag_view(with(60, 3, 1)); }, ErrorCode::bad_message, "DAG_VIEW: traversal");
  expect_rejected([&] { decode_dag_view(with(61, 2, 1)); }, ErrorCode::bad_message, "DAG_VIEW: management");
  expect_rejected([&] { decode_dag_view(with(62, 0, 8)); }, ErrorCode::bad_message, "DAG_VIEW: budget");
  expect_rejected([&] { decode_dag_view(with(62, UINT64_MAX, 8)); }, ErrorCode::bad_message, "DAG_VIEW: budget");
  expect_rejected([&] { decode_dag_view(with(61, 0, 1)); }, ErrorCode::bad_message, "DAG_VIEW: budget: must be 0");
  expect_rejected([&] { decode_dag_view(with(40, 0, 4)); }, ErrorCode::bad_message, "DAG_VIEW: viewport");
  expect_rejected([&] { decode_dag_view(Payload(good.begin(), good.end() - 1)); }, ErrorCode::bad_message, "DAG_VIEW");
}

TEST(HostileInput, OpenResume) {
  auto open_payload = [](uint8_t flags, std::initializer_list<uint32_t> words, const std::vector<int>& bits) {
    Writer w(MessageType::open);
    w.string("m", kMaxNameBytes, "model");
    w.u8(flags);
    for (uint32_t v : words) w.u32(v);
    for (int b : bits) w.bits(uint64_t(b), 1);
    return payload_of(w.finish(), MessageType::open);
  };
  expect_rejected([&] { decode_open(open_payload(16, {}, {})); }, ErrorCode::bad_message, "OPEN: flags: unknown bits");
  expect_rejected([&] { decode_open(open_payload(8 | 2, {}, {})); }, ErrorCode::bad_message,
                  "OPEN: flags: the DAG mode");
  EXPECT_EQ(decode_open(open_payload(8, {}, {})).mode, StreamMode::dag);
  expect_rejected([&] { decode_open(open_payload(0x80, {}, {})); }, ErrorCode::bad_message,
                  "OPEN: flags: unknown bits");
  // Plain (bit 2) is an option of the sender-driven mode: never with view-independent (bit 1), resume or not.
  expect_rejected([&] { decode_open(open_payload(6, {}, {})); }, ErrorCode::bad_message, "OPEN: flags: plain");
  expect_rejected([&] { decode_open(open_payload(7, {1}, {0})); }, ErrorCode::bad_message, "OPEN: flags: plain");
  EXPECT_EQ(decode_open(open_payload(4, {}, {})).mode, StreamMode::sender_plain);
  const Open plain_resume = decode_open(open_payload(5, {1}, {1, 0, 0}));
  EXPECT_EQ(plain_resume.mode, StreamMode::sender_plain);
  EXPECT_EQ(plain_resume.resume.size(), 2u) << "a plain session resumes as a sender-driven one does";
  expect_rejected([&] { decode_open(open_payload(1, {0}, {})); }, ErrorCode::bad_message, "resume tree count: is 0");
  expect_rejected(
      [&] {
        decode_open(open_payload(1, {0xFFFFFFFF}, {0, 0}));
      },
      ErrorCode::bad_message, "resume tree count: count 4294967295 does not fit");
  // 64 "split" bits in a row: a split at depth 63 would need 65-bit node-ids.
  expect_rejected([&] { decode_open(open_payload(1, {1}, std::vector<int>(64, 1))); }, ErrorCode::bad_id,
                  "a split below depth 63");
  // Padding bits must be zero: one tree that is a lone root (bit 0), then a stray 1.
  expect_rejected([&] { decode_open(open_payload(1, {1}, {0, 1})); }, ErrorCode::bad_message, "padding");
  // The leaf limit: 3 trees with 2 leaves each against a limit of 5.
  const Payload six = open_payload(1, {3}, {1, 0, 0, 1, 0, 0, 1, 0, 0});
  EXPECT_EQ(decode_open(six).resume.size(), 6u);
  expect_rejected([&] { decode_open(six, 5); }, ErrorCode::too_large, "more than 5 leaves");

  // The encoder refuses lists that are not a complete front.
  EXPECT_THROW(encode(Open{"m", {{0, 2}}}), Error);                  // <0,3> missing
  EXPECT_THROW(encode(Open{"m", {{0, 1}, {0, 1}}}), Error);          // a duplicate
  EXPECT_THROW(encode(Open{"m", {{0, 1}, {0, 2}, {0, 3}}}), Error);  // a leaf inside another
  EXPECT_THROW(encode(Open{"m", {{1, 1}}}), Error);                  // tree 0 missing
  EXPECT_THROW(encode(Open{"m", {kNoVertex}}), Error);
  EXPECT_NO_THROW(encode(Open{"m", {{0, 2}, {0, 3}, {1, 1}}}));
}

TEST(HostileInput, CatalogueCountIsBoundedByBytes) {
  Writer w(MessageType::catalogue);
  w.u32(0xFFFFFFFF);
  w.u16(0);
  const Payload p = payload_of(w.finish(), MessageType::catalogue);
  expect_rejected([&] { decode_catalogue(p); }, ErrorCode::bad_message, "CATALOGUE: model count: count 4294967295");

  Catalogue bad_flags{{ModelInfo{}}};
  Payload q = payload_of(encode(bad_flags), MessageType::catalogue);
  q.back() = 0x80;
  expect_rejected([&] { decode_catalogue(q); }, ErrorCode::bad_message, "CATALOGUE: model 0: flags: unknown bits");
  q = payload_of(encode(bad_flags), MessageType::catalogue);
  q[q.size() - 3] = 33;  // tree_id_bits
  expect_rejected([&] { decode_catalogue(q); }, ErrorCode::bad_message,
                  "CATALOGUE: model 0: tree_id_bits: not in 1..32");
}

// BASE with one root at the origin of a unit box and the given header fields.
Payload base_payload(uint32_t roots, uint32_t faces, uint8_t tree_bits, uint8_t position_bits, float bbox_min0 = 0,
                     std::initializer_list<uint32_t> corners = {}, uint32_t radius_code = 0,
                     uint32_t axis_code = 1023) {
  Writer w(MessageType::base);
  w.string("m", kMaxNameBytes, "model");
  for (float v : {bbox_min0, 0.0f, 0.0f, 1.0f, 1.0f, 1.0f, 1.0f}) w.f32(v);
  w.u8(tree_bits);
  w.u8(4);
  w.u8(position_bits);
  w.u8(0);
  w.u32(roots);
  w.u32(faces);
  for (uint32_t r = 0; r < std::min(roots, 4u); ++r) {
    for (int k = 0; k < 3; ++k) w.bits(position_bits == 32 ? 0x7FC00000 : 0, position_bits);  // NaN when raw
    // RefineInfo as sent (docs/protocol.md): the flag (0: sent in full), 3 lengths of 11 bits (mu 1), a
    // cone angle of 0, the axis (1023 is 0).
    w.bits(0, 1);
    for (uint32_t v : {radius_code, 1u, 0u}) w.bits(v, 11);
    w.bits(0, 10);
    for (uint32_t v : {axis_code, 1023u}) w.bits(v, 11);
  }
  for (uint32_t v : corners) w.bits(v, tree_bits);
  return payload_of(w.finish(), MessageType::base);
}

TEST(HostileInput, BaseFields) {
  EXPECT_NO_THROW(decode_base(base_payload(3, 1, 2, 8, 0, {0, 1, 2})));
  expect_rejected(
      [&] {
        decode_base(base_payload(3, 1, 2, 8, 0, {0, 1, 3}));
      },
      ErrorCode::bad_id, "BASE: face 0: corner: 3 >= root count 3");
  expect_rejected([&] { decode_base(base_payload(0xFFFFFFF, 0, 28, 8)); }, ErrorCode::bad_message,
                  "BASE: root count: count 268435455 does not fit");
  expect_rejected([&] { decode_base(base_payload(1, 0x7FFFFFFF, 1, 8)); }, ErrorCode::bad_message, "face count");
  expect_rejected([&] { decode_base(base_payload(1, 0, 1, 25)); }, ErrorCode::bad_message, "position bits 25");
  expect_rejected([&] { decode_base(base_payload(3, 0, 1, 8)); }, ErrorCode::bad_message, "cannot hold 3 roots");
  expect_rejected([&] { decode_base(base_payload(1, 0, 1, 8, 2.0f)); }, ErrorCode::bad_message, "min > max");
  expect_rejected([&] { decode_base(base_payload(1, 0, 1, 8, NAN)); }, ErrorCode::bad_message,
                  "bbox min: is not finite");
  expect_rejected([&] { decode_base(base_payload(0, 0, 1, 8)); }, ErrorCode::bad_message, "no roots");
  expect_rejected([&] { decode_base(base_payload(1, 0, 1, 32)); }, ErrorCode::bad_message,
                  "BASE: root 0: position: is not finite");
  EXPECT_NO_THROW(decode_base(base_payload(1, 0, 1, 8, 0, {}, 0x7C0)));  // +inf: "always refine"
  expect_rejected([&] { decode_base(base_payload(1, 0, 1, 8, 0, {}, 0x7C1)); }, ErrorCode::bad_message,
                  "BASE: root 0: refine info: a length is NaN");
  expect_rejected([&] { decode_base(base_payload(1, 0, 1, 8, 0, {}, 0, 2047)); }, ErrorCode::bad_message,
                  "cone axis or angle is out of range");
}

// VSPLITS with one packet written field by field (small_context widths: tree 4, depth 3 bits).
struct RawPacket {
  uint32_t vs_tree = 0, vs_depth = 1;
  uint64_t vs_path = 0;
  unsigned cuts = 1;
  uint32_t cut_tree = 1, cut_depth = 2;
  uint64_t cut_path = 3;
  uint32_t count = 1;
  uint32_t trailing_zero_bytes = 0;  // so a packet shorter than the smallest valid one passes the count check
};
Payload vsplits_payload(const RawPacket& p, const StreamContext& c) {
  Writer w(MessageType::vsplits);
  w.u32(0);
  w.u8(0);
  w.u32(p.count);
  w.bits(p.vs_tree, c.tree_id_bits);
  w.bits(p.vs_depth, 3);
  w.bits(p.vs_path, p.vs_depth);
  w.bits(p.cuts, 2);
  for (int side = 0; side < 2; ++side) {
    if (!(p.cuts & (1u << side))) continue;
    w.bits(p.cut_tree, c.tree_id_bits);
    w.bits(p.cut_depth, 3);
    w.bits(p.cut_path, p.cut_depth);
  }
  for (int k = 0; k < 3; ++k) w.bits(c.grid.bits == 32 ? 0x7F800000 : 0, c.grid.bits);  // +inf when raw
  for (int info = 0; info < 2; ++info) w.bits(1, 1);  // info_t, info_u: mu = delta = 0 (docs/protocol.md)
  for (uint32_t k = 0; k < p.trailing_zero_bytes; ++k) w.u8(0);
  return payload_of(w.finish(), MessageType::vsplits);
}

TEST(HostileInput, VSplitsIds) {
  const StreamContext c = small_context();
  const VSplits ok = decode_vsplits(vsplits_payload({}, c), c);
  ASSERT_EQ(ok.splits.size(), 1u);
  EXPECT_EQ(ok.splits[0].vs, (VertexId{0, 2}));
  EXPECT_EQ(ok.splits[0].cut_l, (VertexId{1, 7}));
  EXPECT_EQ(ok.splits[0].cut_r, kNoVertex);

  RawPacket p;
  p.vs_tree = 10;
  expect_rejected([&] { decode_vsplits(vsplits_payload(p, c), c); }, ErrorCode::bad_id,
                  "VSPLITS: packet 0: v_s: tree-id 10 >= root count 10");
  p = {};
  p.cut_depth = 6;
  p.cut_path = 0;
  expect_rejected([&] { decode_vsplits(vsplits_payload(p, c), c); }, ErrorCode::bad_id, "v_l: depth 6 > the model's 5");
  p = {};
  p.vs_depth = 5;
  expect_rejected([&] { decode_vsplits(vsplits_payload(p, c), c); }, ErrorCode::bad_id,
                  "v_s: <0,32> is at the deepest level");
  p = {};
  p.cuts = 0;
  p.trailing_zero_bytes = 4;
  expect_rejected([&] { decode_vsplits(vsplits_payload(p, c), c); }, ErrorCode::bad_message, "cut flags: neither");
  p = {};
  p.cuts = 2;
  p.cut_tree = 0;
  p.cut_depth = 3;
  p.cut_path = 1;  // <0,9> is below v_s = <0,2>
  expect_rejected([&] { decode_vsplits(vsplits_payload(p, c), c); }, ErrorCode::bad_id,
                  "v_r: <0,9> is inside v_s's subtree");
  p = {};
  p.count = 0x7FFFFFFF;
  expect_rejected([&] { decode_vsplits(vsplits_payload(p, c), c); }, ErrorCode::bad_message,
                  "packet count: count 2147483647 does not fit");
  // More packets than a server may batch, with the bytes to hold them: refused before any is decoded (split
  // records can be as short as their ids, so the count, not the payload, bounds a client's memory).
  p = {};
  p.count = kMaxPacketsPerMessage + 1;
  p.trailing_zero_bytes = (kMaxPacketsPerMessage + 1) * 16;
  expect_rejected([&] { decode_vsplits(vsplits_payload(p, c), c); }, ErrorCode::too_large,
                  "packet count: 65537 > 65536");
  StreamContext raw = c;
  raw.grid.bits = 32;
  expect_rejected([&] { decode_vsplits(vsplits_payload({}, raw), raw); }, ErrorCode::bad_message,
                  "packet 0: position: is not finite");
  StreamContext broken = c;
  broken.root_count = 100;  // more than 4 tree bits hold
  expect_rejected([&] { decode_vsplits(vsplits_payload({}, c), broken); }, ErrorCode::internal,
                  "cannot hold 100 roots");
}

TEST(HostileInput, VSplitsEncoderRefusesWhatTheContextCannotCarry) {
  const StreamContext c = small_context();
  SplitRecord s;
  s.vs = {0, 2};
  s.cut_l = {1, 7};
  EXPECT_NO_THROW(encode(VSplits{0, false, {s}}, c));
  SplitRecord bad = s;
  bad.vs = {10, 1};
  EXPECT_THROW(encode(VSplits{0, false, {bad}}, c), Error);
  bad = s;
  bad.vs = {0, 32};  // depth 5: no deeper level to split into
  EXPECT_THROW(encode(VSplits{0, false, {bad}}, c), Error);
  bad = s;
  bad.cut_l = kNoVertex;
  EXPECT_THROW(encode(VSplits{0, false, {bad}}, c), Error);
  bad = s;
  bad.has_normal = true;
  EXPECT_THROW(encode(VSplits{0, false, {bad}}, c), Error);
}

}  // namespace
}  // namespace pms::protocol
