// Round trips of every message with random values over several seeds: decode(encode(m)) == m (positions
// and normals within their quantization bounds), and encoding is canonical: re-encoding what was decoded
// gives the same bytes.
#include <gtest/gtest.h>
#include <algorithm>
#include <cmath>
#include <cstring>

#include "protocol/client_messages.h"
#include "protocol/dispatch.h"
#include "protocol/framing.h"
#include "protocol/message_types.h"
#include "protocol/model_messages.h"
#include "protocol/packet_bits.h"
#include "protocol/position_grid.h"
#include "protocol/server_messages.h"
#include "protocol/stream_context.h"
#include "protocol_fixtures.h"
#include "spm/hierarchy.h"
#include "spm/refine_info.h"
#include "spm/split_record.h"
#include "spm/vertex_id.h"

namespace pms::protocol {
namespace {

using test::angle_between;
using test::payload_of;
using test::random_float;
using test::random_name;
using test::Rng;

constexpr uint64_t kSeeds[] = {1, 2, 3, 17, 4242};

template <class M, class Decode>
M round_trip(const M& m, MessageType type, Decode decode) {
  const std::vector<uint8_t> frame = encode(m);
  const M back = decode(payload_of(frame, type));
  EXPECT_EQ(encode(back), frame) << "re-encoding " << to_string(type) << " changed its bytes";
  return back;
}

bool same_id(VertexId a, VertexId b) { return a.tree == b.tree && a.node == b.node; }

TEST(Messages, HelloRoundTrip) {
  for (uint64_t seed : kSeeds) {
    Rng rng(seed);
    Hello m;
    m.version = uint16_t(rng());
    m.client_name = random_name(rng, kMaxNameBytes);
    const Hello back = round_trip(m, MessageType::hello, [](auto p) { return decode_hello(p); });
    EXPECT_EQ(back.version, m.version);
    EXPECT_EQ(back.client_name, m.client_name);
  }
}

TEST(Messages, EmptyMessagesRoundTrip) {
  EXPECT_EQ(encode(List{}), (std::vector<uint8_t>{0, 0, 0, 0, 0x02}));
  EXPECT_EQ(encode(Close{}), (std::vector<uint8_t>{0, 0, 0, 0, 0x05}));
  round_trip(List{}, MessageType::list, [](auto p) { return decode_list(p); });
  round_trip(Close{}, MessageType::close, [](auto p) { return decode_close(p); });
}

TEST(Messages, OpenRoundTrip) {
  for (uint64_t seed : kSeeds) {
    Rng rng(seed);
    Open m;
    m.model = random_name(rng, 40);
    const Open fresh = round_trip(m, MessageType::open, [](auto p) { return decode_open(p); });
    EXPECT_EQ(fresh.model, m.model);
    EXPECT_TRUE(fresh.resume.empty());
    EXPECT_EQ(fresh.mode, StreamMode::sender_driven);

    m.mode = StreamMode::view_independent;
    const Open vi = round_trip(m, MessageType::open, [](auto p) { return decode_open(p); });
    EXPECT_EQ(vi.mode, StreamMode::view_independent);
    EXPECT_EQ(encode(m)[kFrameHeaderBytes + 2 + m.model.size()], 2) << "flags: bit 1 = view-independent";
    m.mode = StreamMode::sender_plain;
    const Open plain = round_trip(m, MessageType::open, [](auto p) { return decode_open(p); });
    EXPECT_EQ(plain.mode, StreamMode::sender_plain);
    EXPECT_EQ(encode(m)[kFrameHeaderBytes + 2 + m.model.size()], 4) << "flags: bit 2 = plain (sender-driven option)";
    m.mode = seed % 3 == 0   ? StreamMode::view_independent
             : seed % 3 == 1 ? StreamMode::sender_plain
                             : StreamMode::sender_driven;

    m.resume = test::random_front(rng, uint32_t(1 + rng() % 100), 63);
    const Open back = round_trip(m, MessageType::open, [](auto p) { return decode_open(p); });
    // Decoded in preorder: the same set of leaves.
    auto key = [](VertexId v) { return std::pair{v.tree, v.node}; };
    std::vector<std::pair<uint32_t, uint64_t>> want, got;
    for (VertexId v : m.resume) want.push_back(key(v));
    for (VertexId v : back.resume) got.push_back(key(v));
    std::sort(want.begin(), want.end());
    std::sort(got.begin(), got.end());
    EXPECT_EQ(got, want);
  }
}

TEST(Messages, OpenResumeCostsAboutTwoBitsPerLeaf) {
  Rng rng(5);
  Open m{"bunny", test::random_front(rng, 62, 20)};
  const size_t payload = encode(m).size() - kFrameHeaderBytes;
  const size_t header = 2 + m.model.size() + 1 + 4;
  EXPECT_LE(8 * (payload - header), 2 * m.resume.size() + 7);  // 2F - R bits, padded
}

TEST(Messages, OpenResumeReachesDepth63) {
  // A spine down to the deepest node-id a 64-bit id holds, with its siblings on the way.
  Open m{"deep", {}};
  VertexId v{0, 1};
  for (int depth = 0; depth < 63; ++depth) {
    m.resume.push_back(v.child(1));
    v = v.child(0);
  }
  m.resume.push_back(v);
  ASSERT_EQ(v.depth(), 63);
  const Open back = round_trip(m, MessageType::open, [](auto p) { return decode_open(p); });
  EXPECT_EQ(back.resume.size(), m.resume.size());
}

TEST(Messages, ViewRoundTrip) {
  for (uint64_t seed : kSeeds) {
    Rng rng(seed);
    View m;
    for (int i = 0; i < 3; ++i) {
      m.camera.eye[i] = random_float(rng, -100, 100);
      m.camera.target[i] = random_float(rng, -1, 1);
    }
    m.camera.up[0] = random_float(rng, -0.1f, 0.1f);
    m.camera.up[1] = 1;
    m.camera.up[2] = random_float(rng, -0.1f, 0.1f);
    m.camera.fovy_deg = random_float(rng, 1, 179);
    m.camera.width = uint32_t(1 + rng() % 4096);
    m.camera.height = uint32_t(1 + rng() % 4096);
    m.tolerance = random_float(rng, 0, 10);
    m.frame = uint32_t(rng());
    const View back = round_trip(m, MessageType::view, [](auto p) { return decode_view(p); });
    EXPECT_EQ(std::memcmp(&back.camera, &m.camera, sizeof m.camera), 0);  // bit-identical: make_view agrees
    EXPECT_EQ(back.tolerance, m.tolerance);
    EXPECT_EQ(back.frame, m.frame);
  }
}

// AHEAD is VIEW's payload under its own type; a batch sent ahead is never final, and a decoder refuses both bits.
TEST(Messages, AheadRoundTripAndAheadBatchesAreNeverFinal) {
  View view;
  view.camera.eye[2] = 3;
  view.frame = 12;
  const Ahead back = round_trip(Ahead{view}, MessageType::ahead, [](auto p) { return decode_ahead(p); });
  EXPECT_EQ(std::memcmp(&back.view.camera, &view.camera, sizeof view.camera), 0);
  EXPECT_EQ(back.view.frame, 12u);
  Frame frame{MessageType::ahead, payload_of(encode(Ahead{view}), MessageType::ahead)};
  EXPECT_TRUE(std::holds_alternative<Ahead>(decode_client_message(frame)));

  Rng rng(3);
  const StreamContext c = test::random_context(rng);
  VSplits batch{5, true, {test::random_split(rng, c)}, true};
  EXPECT_THROW(encode(batch, c), Error);
  batch.final = false;
  std::vector<uint8_t> payload = payload_of(encode(batch, c), MessageType::vsplits);
  EXPECT_TRUE(decode_vsplits(payload, c).ahead);
  payload[4] = 3;  // final and ahead
  test::expect_rejected([&] { decode_vsplits(payload, c); }, ErrorCode::bad_message, "final and ahead");
  payload[4] = 4;
  test::expect_rejected([&] { decode_vsplits(payload, c); }, ErrorCode::bad_message, "unknown bits");
}

TEST(Messages, HelloOkRoundTrip) {
  for (uint64_t seed : kSeeds) {
    Rng rng(seed);
    HelloOk m{uint16_t(rng()), random_name(rng, 100), uint32_t(rng()), uint32_t(rng())};
    const HelloOk back = round_trip(m, MessageType::hello_ok, [](auto p) { return decode_hello_ok(p); });
    EXPECT_EQ(back.version, m.version);
    EXPECT_EQ(back.server_name, m.server_name);
    EXPECT_EQ(back.max_client_message, m.max_client_message);
    EXPECT_EQ(back.max_server_message, m.max_server_message);
  }
}

TEST(Messages, CatalogueRoundTrip) {
  for (uint64_t seed : kSeeds) {
    Rng rng(seed);
    Catalogue m;
    m.models.resize(rng() % 20);
    for (ModelInfo& info : m.models)
      info = {random_name(rng, 30), rng(),           uint32_t(rng()), rng(), uint32_t(1 + rng() % 32),
              uint32_t(rng() % 64), bool(rng() & 1), bool(rng() & 1)};
    const Catalogue back = round_trip(m, MessageType::catalogue, [](auto p) { return decode_catalogue(p); });
    ASSERT_EQ(back.models.size(), m.models.size());
    for (size_t i = 0; i < m.models.size(); ++i) {
      const ModelInfo &a = m.models[i], &b = back.models[i];
      EXPECT_EQ(b.name, a.name);
      EXPECT_EQ(b.input_faces, a.input_faces);
      EXPECT_EQ(b.base_vertices, a.base_vertices);
      EXPECT_EQ(b.vsplits, a.vsplits);
      EXPECT_EQ(b.tree_id_bits, a.tree_id_bits);
      EXPECT_EQ(b.node_id_bits, a.node_id_bits);
      EXPECT_EQ(b.has_normals, a.has_normals);
      EXPECT_EQ(b.has_colors, a.has_colors);
    }
  }
}

TEST(Messages, ErrorRoundTrip) {
  for (uint64_t seed : kSeeds) {
    Rng rng(seed);
    ErrorMessage m{ErrorCode(1 + rng() % 9), random_name(rng, 3000)};
    const ErrorMessage back = round_trip(m, MessageType::error, [](auto p) { return decode_error(p); });
    EXPECT_EQ(back.code, m.code);
    EXPECT_EQ(back.text, m.text);
  }
  // A code from a newer server passes through.
  const ErrorMessage future{ErrorCode(77), "new"};
  EXPECT_EQ(decode_error(payload_of(encode(future), MessageType::error)).code, ErrorCode(77));
  EXPECT_EQ(to_string(ErrorCode(77)), "code 77");
}

Base random_base(Rng& rng) {
  const StreamContext c = test::random_context(rng);
  Base m;
  m.model = random_name(rng, 20);
  for (int i = 0; i < 3; ++i) {
    m.bbox_min[i] = c.grid.min[i];
    m.bbox_max[i] = c.grid.max[i];
  }
  m.scale = random_float(rng, 0, 10);
  const uint32_t roots = uint32_t(1 + rng() % std::min<uint64_t>(c.root_count, 300));
  m.tree_id_bits = std::max(c.tree_id_bits, tree_id_bits(roots));
  m.node_id_bits = c.node_id_bits;
  m.position_bits = c.grid.bits;
  m.has_normals = c.has_normals;
  m.has_colors = c.has_colors;
  for (uint32_t i = 0; i < roots; ++i) {
    for (int k = 0; k < 3; ++k) m.positions.push_back(random_float(rng, m.bbox_min[k], m.bbox_max[k]));
    m.refine.push_back(test::random_refine(rng));
    if (m.has_normals) {
      const float n[3] = {random_float(rng, -1, 1), random_float(rng, -1, 1), random_float(rng, -1, 1)};
      const float length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
      for (float v : n) m.normals.push_back(v / length);
    }
    if (m.has_colors)
      for (int k = 0; k < 4; ++k) m.colors.push_back(uint8_t(rng()));
  }
  const size_t faces = rng() % 500;
  for (size_t f = 0; f < 3 * faces; ++f) m.faces.push_back(uint32_t(rng() % roots));
  return m;
}

TEST(Messages, BaseRoundTrip) {
  for (uint64_t seed : kSeeds) {
    Rng rng(seed);
    const Base m = random_base(rng);
    const Base back = round_trip(m, MessageType::base, [](auto p) { return decode_base(p); });
    EXPECT_EQ(back.model, m.model);
    EXPECT_EQ(std::memcmp(back.bbox_min, m.bbox_min, sizeof m.bbox_min), 0);
    EXPECT_EQ(std::memcmp(back.bbox_max, m.bbox_max, sizeof m.bbox_max), 0);
    EXPECT_EQ(back.scale, m.scale);
    EXPECT_EQ(back.tree_id_bits, m.tree_id_bits);
    EXPECT_EQ(back.node_id_bits, m.node_id_bits);
    EXPECT_EQ(back.position_bits, m.position_bits);
    EXPECT_EQ(back.refine, m.refine);
    EXPECT_EQ(back.colors, m.colors);
    EXPECT_EQ(back.faces, m.faces);
    const StreamContext c = stream_context(back);
    ASSERT_EQ(back.positions.size(), m.positions.size());
    for (size_t i = 0; i < m.positions.size(); ++i) {
      EXPECT_LE(std::abs(back.positions[i] - m.positions[i]), position_error_bound(c.grid, int(i % 3)));
      float snapped[3];
      snap_position(c.grid, &m.positions[i - i % 3], snapped);
      EXPECT_EQ(back.positions[i], snapped[i % 3]) << "client and server must see the same position";
    }
    ASSERT_EQ(back.normals.size(), m.normals.size());
    for (size_t i = 0; i < m.normals.size(); i += 3) {
      EXPECT_LT(angle_between(&back.normals[i], &m.normals[i]), 1e-4);
    }
  }
}

TEST(Messages, VSplitsRoundTrip) {
  for (uint64_t seed : kSeeds) {
    for (int round = 0; round < 20; ++round) {
      Rng rng(seed * 1000 + round);
      StreamContext c = test::random_context(rng);
      c.has_refinement = round % 3 != 0;  // a view-independent session's packets have no info_t / info_u
      VSplits m;
      m.frame = uint32_t(rng());
      m.final = rng() & 1;
      m.ahead = !m.final && round % 4 == 1;
      m.splits.resize(rng() % 200);
      for (SplitRecord& s : m.splits) s = test::random_split(rng, c);
      const std::vector<uint8_t> frame = encode(m, c);
      const VSplits back = decode_vsplits(payload_of(frame, MessageType::vsplits), c);
      EXPECT_EQ(back.frame, m.frame);
      EXPECT_EQ(back.final, m.final);
      EXPECT_EQ(back.ahead, m.ahead);
      ASSERT_EQ(back.splits.size(), m.splits.size());
      uint64_t bits = 0;
      for (size_t i = 0; i < m.splits.size(); ++i) {
        const SplitRecord &a = m.splits[i], &b = back.splits[i];
        EXPECT_TRUE(same_id(b.vs, a.vs) && same_id(b.cut_l, a.cut_l) && same_id(b.cut_r, a.cut_r))
            << "packet " << i << ": " << to_string(b.vs) << " " << to_string(a.vs);
        float snapped[3];
        snap_position(c.grid, a.position_t, snapped);
        EXPECT_EQ(std::memcmp(b.position_t, snapped, sizeof snapped), 0);
        EXPECT_EQ(b.info_t, c.has_refinement ? as_sent(a.info_t) : RefineInfo{});
        EXPECT_EQ(b.info_u, c.has_refinement ? as_sent(a.info_u) : RefineInfo{});
        EXPECT_EQ(b.has_normal, c.has_normals);
        if (c.has_normals) {
          EXPECT_LT(angle_between(b.normal_t, a.normal_t), 1e-4);
        }
        EXPECT_EQ(b.has_color, c.has_colors);
        if (c.has_colors) {
          EXPECT_EQ(std::memcmp(b.color_t, a.color_t, 4), 0);
        }
        const auto info_bits = [](const RefineInfo& info) {  // docs/protocol.md: flag, lengths, angle, axis
          if (info.mu == 0 && info.delta == 0) return 1u;
          return info.cone_angle == kNoCone ? 44u : 66u;
        };
        const uint32_t info_bits_sum = info_bits(a.info_t) + info_bits(a.info_u);
        EXPECT_EQ(packet_bits(a, c).refinement, c.has_refinement ? info_bits_sum : 0u);
        bits += packet_bits(a, c).total();
      }
      // packet_bits is exact: header (4 + 1 + 4 bytes) + the packets' bits, padded once.
      EXPECT_EQ(frame.size(), kFrameHeaderBytes + 9 + (bits + 7) / 8);
      // Canonical where the grid is coarser than float resolution over the box (always here up to 20 bits).
      if (c.grid.bits <= 20 || c.grid.bits == 32) {
        EXPECT_EQ(encode(back, c), frame);
      }
    }
  }
}

TEST(Messages, EncoderRefusesRefinementInfoFinerThanStored) {
  Rng rng(5);
  StreamContext c = test::random_context(rng);
  VSplits m;
  m.splits.push_back(test::random_split(rng, c));
  m.splits[0].info_u.radius |= 1;  // a bit the wire does not carry: the two ends would disagree
  EXPECT_THROW(encode(m, c), Error);
}

TEST(Messages, DispatchByDirection) {
  const std::vector<uint8_t> hello = encode(Hello{kProtocolVersion, "test"});
  Frame frame{MessageType::hello, payload_of(hello, MessageType::hello)};
  EXPECT_TRUE(std::holds_alternative<Hello>(decode_client_message(frame)));
  test::expect_rejected([&] { decode_server_message(frame, nullptr); }, ErrorCode::bad_message,
                        "HELLO: not a message a server sends");

  frame = {MessageType::error, payload_of(encode(ErrorMessage{ErrorCode::timeout, "late"}), MessageType::error)};
  const ServerMessage reply = decode_server_message(frame, nullptr);
  ASSERT_TRUE(std::holds_alternative<ErrorMessage>(reply));
  EXPECT_EQ(std::get<ErrorMessage>(reply).code, ErrorCode::timeout);
  test::expect_rejected([&] { decode_client_message(frame); }, ErrorCode::bad_message,
                        "ERROR: not a message a client sends");

  frame = {MessageType(0x42), {}};
  test::expect_rejected([&] { decode_client_message(frame); }, ErrorCode::bad_message, "type 0x42");

  Rng rng(9);
  const StreamContext c = test::random_context(rng);
  VSplits batch{7, true, {test::random_split(rng, c)}};
  frame = {MessageType::vsplits, payload_of(encode(batch, c), MessageType::vsplits)};
  test::expect_rejected([&] { decode_server_message(frame, nullptr); }, ErrorCode::out_of_order, "before any BASE");
  EXPECT_EQ(std::get<VSplits>(decode_server_message(frame, &c)).frame, 7u);
}

// DAG_OPS: collapse ids then packets, through the dispatcher (which needs a BASE's context, as VSPLITS does).
TEST(Messages, DagOpsAndDagViewRoundTrip) {
  Rng rng(11);
  StreamContext c = test::random_context(rng);
  c.has_refinement = false;
  DagOps ops{12, true, {}, {}};
  for (int i = 0; i < 5; ++i) {
    ops.collapses.push_back(test::random_split(rng, c).vs);
    ops.splits.push_back(test::random_split(rng, c));
  }
  const std::vector<uint8_t> bytes = encode(ops, c);
  Frame frame{MessageType::dag_ops, payload_of(bytes, MessageType::dag_ops)};
  test::expect_rejected([&] { decode_server_message(frame, nullptr); }, ErrorCode::out_of_order,
                        "DAG_OPS: before any BASE");
  const DagOps back = std::get<DagOps>(decode_server_message(frame, &c));
  EXPECT_EQ(back.frame, 12u);
  EXPECT_TRUE(back.final);
  EXPECT_EQ(back.collapses, ops.collapses);
  ASSERT_EQ(back.splits.size(), ops.splits.size());
  EXPECT_EQ(encode(back, c), bytes);

  DagView view;
  view.view.frame = 3;
  view.traversal = DagTraversal::linear;
  view.max_ops = 77;
  const std::vector<uint8_t> request = encode(view);
  EXPECT_EQ(request.size(), kFrameHeaderBytes + 70);
  frame = {MessageType::dag_view, payload_of(request, MessageType::dag_view)};
  const DagView got = std::get<DagView>(decode_client_message(frame));
  EXPECT_EQ(got.view.frame, 3u);
  EXPECT_EQ(got.traversal, DagTraversal::linear);
  EXPECT_EQ(got.max_ops, 77u);
  EXPECT_EQ(got.management, DagMode::free);
}

}  // namespace
}  // namespace pms::protocol
