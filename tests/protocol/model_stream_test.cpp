// Real models through the codecs: BASE and every vsplit packet of a built sphere (with normals and
// colors), terrain and the bunny are encoded in batches, cut into random chunks, framed, decoded, and
// fed to the client's hierarchy (spm/vertex_hierarchy.h), which must refine to the full input. Also the packet
// sizes the bench (E2, kim-lee-kobbelt Table 2) reports: topology bits per packet <= 96.
#include <gtest/gtest.h>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>

#include "common/bit_stream.h"
#include "io/shapes.h"
#include "protocol/client_messages.h"
#include "protocol/dispatch.h"
#include "protocol/framing.h"
#include "protocol/message_types.h"
#include "protocol/model_messages.h"
#include "protocol/packet_bits.h"
#include "protocol/packet_table.h"
#include "protocol/position_grid.h"
#include "protocol/server_messages.h"
#include "protocol/split_bands.h"
#include "protocol/stream_context.h"
#include "protocol_fixtures.h"
#include "spm/hierarchy.h"
#include "spm/selective_mesh.h"
#include "spm/split_codec.h"
#include "spm/split_record.h"
#include "spm/vertex_hierarchy.h"
#include "spm/vertex_id.h"
#include "test_support.h"

namespace pms::protocol {
namespace {

constexpr size_t kBatch = 2048;

struct PacketStats {
  size_t packets = 0;
  uint64_t topology = 0, position = 0, refinement = 0, attributes = 0;
  uint64_t aligned_bytes = 0;  // if every packet were padded to a byte
  uint64_t stream_bytes = 0;   // VSPLITS frames as sent (headers included)
  uint32_t max_topology = 0;
};

struct Received {
  Base base;
  StreamContext context;
  std::vector<SplitRecord> splits;
};

// The server side: BASE, then the split order in VSPLITS batches; the client side: a FrameReader fed in
// random chunks and the direction's dispatcher.
Received stream_model(const ModelData& model, const std::string& name, uint32_t position_bits, PacketStats& stats) {
  const Base base = make_base(model, name, position_bits);
  const StreamContext server_context = stream_context(base);
  std::vector<uint8_t> wire = encode(base);
  for (size_t first = 0; first < model.split_order.size(); first += kBatch) {
    VSplits batch;
    batch.frame = uint32_t(first / kBatch);
    const size_t last = std::min(model.split_order.size(), first + kBatch);
    batch.final = last == model.split_order.size();
    for (size_t i = first; i < last; ++i) {
      batch.splits.push_back(split_record(model, model.split_order[i]));
      const PacketBits bits = packet_bits(batch.splits.back(), server_context);
      stats.topology += bits.topology;
      stats.position += bits.position;
      stats.refinement += bits.refinement;
      stats.attributes += bits.attributes;
      stats.aligned_bytes += (bits.total() + 7) / 8;
      stats.max_topology = std::max(stats.max_topology, bits.topology);
    }
    const std::vector<uint8_t> frame = encode(batch, server_context);
    stats.stream_bytes += frame.size();
    stats.aligned_bytes += kFrameHeaderBytes + 9;
    wire.insert(wire.end(), frame.begin(), frame.end());
  }
  stats.packets = model.split_order.size();

  Received got;
  FrameReader reader;
  test::Rng rng(position_bits);
  bool have_base = false;
  for (size_t at = 0; at < wire.size();) {
    const size_t take = std::min<size_t>(wire.size() - at, 1 + rng() % 5000);
    reader.feed(wire.data() + at, take);
    at += take;
    Frame frame;
    while (reader.next(frame)) {
      ServerMessage message = decode_server_message(frame, have_base ? &got.context : nullptr);
      if (auto* b = std::get_if<Base>(&message)) {
        got.base = std::move(*b);
        got.context = stream_context(got.base);
        have_base = true;
      } else {
        auto& batch = std::get<VSplits>(message);
        got.splits.insert(got.splits.end(), batch.splits.begin(), batch.splits.end());
      }
    }
  }
  EXPECT_FALSE(reader.mid_frame());
  return got;
}

void expect_same_packets(const ModelData& model, const Received& got) {
  const StreamContext& c = got.context;
  ASSERT_EQ(got.splits.size(), model.split_order.size());
  for (size_t i = 0; i < got.splits.size(); ++i) {
    const SplitRecord want = split_record(model, model.split_order[i]);
    const SplitRecord& s = got.splits[i];
    ASSERT_TRUE(s.vs == want.vs && s.cut_l == want.cut_l && s.cut_r == want.cut_r) << "packet " << i;
    float snapped[3];
    snap_position(c.grid, want.position_t, snapped);
    ASSERT_EQ(std::memcmp(s.position_t, snapped, sizeof snapped), 0)
        << "packet " << i << ": client and server positions differ";
    ASSERT_EQ(s.info_t, as_sent(want.info_t));
    ASSERT_EQ(s.info_u, as_sent(want.info_u));
    ASSERT_EQ(s.has_normal, want.has_normal);
    ASSERT_EQ(s.has_color, want.has_color);
    if (s.has_color) {
      ASSERT_EQ(std::memcmp(s.color_t, want.color_t, 4), 0);
    }
    if (s.has_normal) {
      ASSERT_LT(test::angle_between(s.normal_t, want.normal_t), 1e-4) << "packet " << i;
    }
  }
}

// The client's side of kim-lee-kobbelt §5.3: UpdateVHierarchy for every packet, then SelVSplit in
// arrival order; the result is the full input.
void expect_client_refines_fully(const ModelData& model, const Received& got, const std::string& name) {
  const Base& base = got.base;
  VertexHierarchy hierarchy(base.has_normals, base.has_colors);
  for (uint32_t r = 0; r < base.root_count(); ++r)
    hierarchy.add_root({r, 1}, &base.positions[3 * size_t(r)], base.refine[r],
                       base.has_normals ? &base.normals[3 * size_t(r)] : nullptr,
                       base.has_colors ? &base.colors[4 * size_t(r)] : nullptr);
  for (const SplitRecord& s : got.splits) hierarchy.add_split(s);
  SelectiveMesh mesh(hierarchy, base.faces);
  for (const SplitRecord& s : got.splits) {
    ASSERT_TRUE(mesh.vsplit(hierarchy.find(s.vs)).done);
  }
  std::string why;
  ASSERT_TRUE(mesh.check_invariants(&why)) << why;
  const ModelInfo info = model_info(model, name);
  EXPECT_EQ(mesh.face_count(), info.input_faces);
  EXPECT_EQ(mesh.vertex_count(), (model.node_count() + model.root_count) / 2);
  // Every node's position on the client is the server's snapped one.
  for (uint32_t n = 0; n < model.node_count(); ++n) {
    const uint32_t slot = hierarchy.find(model.id(n));
    ASSERT_NE(slot, kNone);
    float snapped[3];
    snap_position(got.context.grid, &model.position[3 * size_t(n)], snapped);
    ASSERT_EQ(std::memcmp(hierarchy.position(slot), snapped, sizeof snapped), 0) << "node " << n;
  }
}

void report(const char* name, const StreamContext& c, const PacketStats& s) {
  const double n = double(s.packets);
  std::printf(
      "[ %-8s ] tree %u bits, node %u bits, %zu packets: topology %.1f bits (max %u), position %.0f, "
      "refinement %.0f, attributes %.0f; %.2f bytes/packet as one bit stream per batch, %.2f byte-aligned\n",
      name, c.tree_id_bits, c.node_id_bits, s.packets, s.topology / n, s.max_topology, s.position / n, s.refinement / n,
      s.attributes / n, s.stream_bytes / n, s.aligned_bytes / n);
  ::testing::Test::RecordProperty(std::string(name) + "_topology_bits_mean", std::to_string(s.topology / n));
  ::testing::Test::RecordProperty(std::string(name) + "_bytes_per_packet", std::to_string(s.stream_bytes / n));
}

void check_model(const test::BuiltModel& built, uint32_t position_bits = kDefaultPositionBits) {
  const ModelData model = built.model();
  PacketStats stats;
  const Received got = stream_model(model, built.name, position_bits, stats);
  ASSERT_NO_FATAL_FAILURE(expect_same_packets(model, got));
  ASSERT_NO_FATAL_FAILURE(expect_client_refines_fully(model, got, built.name));
  report(built.name.c_str(), got.context, stats);
  EXPECT_LE(double(stats.topology) / double(stats.packets), 96.0) << "kim-lee-kobbelt Table 2: 96 bits";
  EXPECT_LE(stats.stream_bytes, stats.aligned_bytes) << "a bit stream per batch is never larger";
}

TEST(ModelStream, SphereWithNormalsAndColors) {
  ASSERT_FALSE(test::sphere_model().hierarchy.normals.empty());
  check_model(test::sphere_model());
}

TEST(ModelStream, Terrain) { check_model(test::terrain_model()); }

TEST(ModelStream, TerrainRawFloatsAndCoarseGrid) {
  check_model(test::terrain_model(), 32);
  check_model(test::terrain_model(), 10);
}

TEST(ModelStream, Bunny) {
  PMS_REQUIRE_SHARED_MODEL(path, "bunny.ply.xz");
  const test::BuiltModel* bunny = test::bunny_model();
  ASSERT_NE(bunny, nullptr);
  check_model(*bunny);
}

// The server's encoded-once packets (v_s's id and its stored record) make the very frames the encoder
// makes, in any order and batch size.
void check_packet_table(const test::BuiltModel& built, uint32_t position_bits) {
  const ModelData model = built.model();
  StreamContext c = stream_context(make_base(model, built.name, position_bits));
  c.has_refinement = true;
  const EncodedRecords stored = encode_records(model, position_bits);
  BitReader tables(stored.tables, "tables");
  c.records = std::make_shared<const SplitCodec>(SplitCodec::deserialize(tables));
  const std::vector<uint32_t> q = grid_positions(model, position_bits);
  c.held = [&](VertexId id, SplitContext& out) {
    out = split_context(model, q, model.find(id));
    return true;
  };
  const PacketTable table(model, c, StoredRecords{stored.records, stored.offsets});
  test::Rng rng(position_bits);
  for (int round = 0; round < 40; ++round) {
    VSplits m;
    m.frame = uint32_t(rng());
    m.final = rng() & 1;
    std::vector<uint32_t> nodes;
    const size_t count = round == 0 ? 0 : rng() % 300;
    std::vector<bool> taken(model.node_count());  // a batch splits a node once
    while (nodes.size() < count) {
      const uint32_t node = model.split_order[rng() % model.split_order.size()];
      if (taken[node]) continue;
      taken[node] = true;
      nodes.push_back(node);
      m.splits.push_back(split_record(model, node));
    }
    ASSERT_EQ(table.encode(m.frame, m.final, nodes), encode(m, c)) << "round " << round;
  }
  const uint32_t leaf = uint32_t(model.node_count() - 1);  // nothing follows it to be its children
  ASSERT_TRUE(model.is_leaf(leaf));
  EXPECT_THROW(table.encode(1, true, std::vector<uint32_t>{leaf}), Error);
  EXPECT_THROW(table.encode(1, true, std::vector<uint32_t>{uint32_t(model.node_count())}), Error);
}

TEST(ModelStream, PacketTableMakesTheEncodersFrames) {
  check_packet_table(test::sphere_model(), kDefaultPositionBits);
  check_packet_table(test::terrain_model(), kDefaultPositionBits);
  check_packet_table(test::terrain_model(), 32);
  check_packet_table(test::terrain_model(), 10);
}

TEST(ModelStream, BunnyTopologyBitsPerPacket) {
  PMS_REQUIRE_SHARED_MODEL(path, "bunny.ply.xz");
  const ModelData model = test::bunny_model()->model();
  const StreamContext c = stream_context(make_base(model, "bunny"));
  uint64_t total = 0;
  uint32_t worst = 0;
  for (uint32_t node : model.split_order) {
    const uint32_t bits = packet_bits(split_record(model, node), c).topology;
    total += bits;
    worst = std::max(worst, bits);
  }
  const double mean = double(total) / double(model.split_order.size());
  std::printf("[ bunny    ] topology bits per vsplit packet: mean %.2f, max %u (kim-lee-kobbelt Table 2: 96)\n", mean,
              worst);
  EXPECT_LE(mean, 96.0);
  // The worst packet: three ids at full depth plus the flags.
  EXPECT_LE(worst, 2 + 3 * (c.tree_id_bits + depth_field_bits(c.node_id_bits) + c.node_id_bits));
}

TEST(ModelStream, ResumeFrontOfAFullyRefinedBunny) {
  PMS_REQUIRE_SHARED_MODEL(path, "bunny.ply.xz");
  const ModelData model = test::bunny_model()->model();
  Open open{"bunny", {}};
  for (uint32_t n = 0; n < model.node_count(); ++n)
    if (model.is_leaf(n)) open.resume.push_back(model.id(n));
  const std::vector<uint8_t> frame = encode(open);
  const Open back = decode_open(test::payload_of(frame, MessageType::open));
  ASSERT_EQ(back.resume.size(), open.resume.size());
  for (VertexId v : back.resume) {
    ASSERT_NE(model.find(v), kNone);
  }
  std::printf("[ bunny    ] OPEN resume with all %zu leaves: %zu bytes (%.2f bits per leaf)\n", open.resume.size(),
              frame.size(), 8.0 * double(frame.size()) / double(open.resume.size()));
  EXPECT_LT(frame.size(), open.resume.size() / 4 + 64);  // about 2 bits per leaf
}

TEST(ModelStream, ModelInfoCountsTheInput) {
  const ModelData model = test::sphere_model().model();
  const ModelInfo info = model_info(model, "sphere");
  const Mesh sphere = make_sphere(24, 32);
  EXPECT_EQ(info.input_faces, sphere.face_count());
  EXPECT_EQ(info.vsplits, sphere.vertex_count() - model.root_count);
  EXPECT_TRUE(info.has_normals);
  EXPECT_TRUE(info.has_colors);
  const Catalogue catalogue{{info}};
  EXPECT_EQ(decode_catalogue(test::payload_of(encode(catalogue), MessageType::catalogue)).models[0].input_faces,
            info.input_faces);
}

}  // namespace
}  // namespace pms::protocol
