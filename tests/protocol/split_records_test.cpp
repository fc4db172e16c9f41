// Compressed split records (spm/split_codec.h) on real models at the wire's 16-bit grid: every record of the
// bunny, the horse (normals) and a sphere with normals and colors round-trips, a client that holds only
// what the base mesh and earlier records gave it decodes them (its contexts come from its own
// VertexHierarchy, not from the model), it ends with the model's quantized values, and the bits per part
// are printed beside the full VSPLITS packet bits.
#include <gtest/gtest.h>

#include <cstdio>
#include <vector>

#include "common/bit_stream.h"
#include "protocol/model_messages.h"
#include "protocol/packet_bits.h"
#include "protocol/position_grid.h"
#include "protocol/server_messages.h"
#include "protocol/split_bands.h"
#include "protocol/stream_context.h"
#include "protocol/wire_internal.h"
#include "protocol_fixtures.h"
#include "spm/hierarchy.h"
#include "spm/split_codec.h"
#include "spm/split_record.h"
#include "spm/vertex_hierarchy.h"

namespace pms::protocol {
namespace {

struct RecordStats {
  size_t splits = 0;
  RecordBits bits;
  PacketBits today;  // the same splits as VSPLITS packets, summed
  uint64_t table_bits = 0;
};

// Encodes every split of the model as the .pms file stores them, decodes each stored record through a
// client that receives them in split order, checks it against the model, and sums the bits.
RecordStats check_records(const ModelData& model, uint32_t position_bits) {
  const PositionGrid grid = model_grid(model, position_bits);
  const std::vector<uint32_t> q = grid_positions(model, position_bits);
  const EncodedRecords stored = encode_records(model, position_bits);  // what the .pms file holds
  RecordStats stats;
  stats.table_bits = 8 * stored.tables.size();
  BitReader table_reader(stored.tables, "tables");
  const SplitCodec client_codec = SplitCodec::deserialize(table_reader);

  // The roots as BASE delivers them: snapped positions, info as sent, normals through the wire's octahedral code.
  const Base base = decode_base(test::payload_of(encode(make_base(model, "model", position_bits)), MessageType::base));
  const StreamContext context = stream_context(base);
  VertexHierarchy client(base.has_normals, base.has_colors);
  for (uint32_t r = 0; r < model.root_count; ++r)
    client.add_root(model.id(r), &base.positions[3 * size_t(r)], base.refine[r],
                    base.has_normals ? &base.normals[3 * size_t(r)] : nullptr,
                    base.has_colors ? &base.colors[4 * size_t(r)] : nullptr);
  for (uint32_t node : model.split_order) {
    BitWriter w;
    RecordBits parts;
    const SplitPayload sent = split_payload(model, q, node);
    client_codec.encode(split_context(model, q, node), sent, w, &parts);
    EXPECT_EQ(w.size(), stored.offsets[node + 1] - stored.offsets[node]);  // the same tables code it the same way
    stats.bits += parts;
    ++stats.splits;
    const PacketBits today = packet_bits(split_record(model, node), context);
    stats.today.topology += today.topology, stats.today.position += today.position,
        stats.today.refinement += today.refinement, stats.today.attributes += today.attributes;

    const uint32_t slot = client.find(model.id(node));
    EXPECT_NE(slot, kNone);
    if (slot == kNone) break;
    BitReader r(stored.records, stored.offsets[node], stored.offsets[node + 1], "record");
    const SplitPayload got = client_codec.decode(held_split_context(client, slot, grid), r);
    EXPECT_EQ(r.bits_left(), 0u);
    EXPECT_EQ(got, sent) << "split of " << to_string(model.id(node));
    if (!(got == sent)) break;
    client.add_split(split_record_of(model.id(node), got, grid, client_codec));
  }
  // The client now holds every node with the values every mode evaluates: snapped positions, info as sent,
  // normals as the wire's octahedral code gives them back, the colors.
  for (uint32_t n = 0; n < model.node_count(); ++n) {
    const uint32_t slot = client.find(model.id(n));
    EXPECT_NE(slot, kNone);
    if (slot == kNone) break;
    float p[3];
    snap_position(grid, &model.position[3 * size_t(n)], p);
    for (int k = 0; k < 3; ++k) EXPECT_EQ(client.position(slot)[k], p[k]);
    EXPECT_EQ(client.refine(slot), as_sent(model.refine[n]));
    if (!model.normals.empty()) {
      uint16_t q[2];
      float sent[3];
      encode_normal(&model.normals[3 * size_t(n)], q);
      decode_normal(q, sent);
      for (int k = 0; k < 3; ++k) EXPECT_EQ(client.normal(slot)[k], sent[k]) << "normal of node " << n;
    }
    if (!model.colors.empty()) {
      for (int k = 0; k < 4; ++k)
        EXPECT_EQ(client.color(slot)[k], model.colors[4 * size_t(n) + k]) << "color of node " << n;
    }
  }
  return stats;
}

void print(const char* name, const RecordStats& s) {
  const double n = double(s.splits);
  std::printf(
      "%s: %zu records, bits per split: topology %.2f, geometry %.2f, refinement %.2f, normal %.2f, "
      "color %.2f, total %.2f; tables %.1f KB\n"
      "  full VSPLITS packets: topology %.2f (v_s id included), position %.2f, refinement %.2f, attributes %.2f\n",
      name, s.splits, double(s.bits.topology) / n, double(s.bits.geometry) / n, double(s.bits.refinement) / n,
      double(s.bits.normal) / n, double(s.bits.color) / n, double(s.bits.total()) / n, double(s.table_bits) / 8192,
      double(s.today.topology) / n, double(s.today.position) / n, double(s.today.refinement) / n,
      double(s.today.attributes) / n);
}

uint64_t full_bits(const RecordStats& s) {
  return s.today.topology + s.today.position + s.today.refinement + s.today.attributes;
}

TEST(SplitRecords, TerrainRoundTripsThroughAClient) {
  const RecordStats s = check_records(test::terrain_model().model(), 16);
  print("terrain", s);
  EXPECT_LT(s.bits.total(), full_bits(s));
}

TEST(SplitRecords, SphereWithNormalsAndColorsRoundTripsThroughAClient) {
  const ModelData model = test::sphere_model().model();
  ASSERT_FALSE(model.normals.empty());
  ASSERT_FALSE(model.colors.empty());
  const RecordStats s = check_records(model, 16);
  print("sphere with normals and colors", s);
  EXPECT_GT(s.bits.normal, 0u);
  EXPECT_GT(s.bits.color, 0u);
  EXPECT_LT(s.bits.total(), full_bits(s));
}

TEST(SplitRecords, EveryHorseRecordRoundTripsThroughAClient) {
  const test::BuiltModel* horse = test::horse_model();
  if (!horse) GTEST_SKIP() << "../shared/models/horse.ply.xz not found: this test needs the shared test meshes";
  const ModelData model = horse->model();
  ASSERT_FALSE(model.normals.empty()) << "the horse has normals";
  const RecordStats s = check_records(model, 16);
  print("horse", s);
  EXPECT_EQ(s.splits, model.split_order.size());
  EXPECT_LT(s.bits.total(), full_bits(s));
}

TEST(SplitRecords, CoarseGridRoundTrips) {
  const RecordStats s = check_records(test::terrain_model().model(), 10);
  EXPECT_GT(s.splits, 0u);
}

// Float positions (32 bits) and the finest grid: position differences whose raw bits pass the 24 a symbol
// log word holds inline (the stored records are coded from the fit's log; check_records compares each with
// a record coded on its own).
TEST(SplitRecords, FloatPositionsAndTheFinestGridRoundTrip) {
  for (uint32_t bits : {24u, 32u}) {
    const RecordStats s = check_records(test::terrain_model().model(), bits);
    EXPECT_GT(s.splits, 0u) << bits << " bits";
  }
}

TEST(SplitRecords, EveryBunnyRecordRoundTripsThroughAClient) {
  const test::BuiltModel* bunny = test::bunny_model();
  if (!bunny) GTEST_SKIP() << "../shared/models/bunny.ply.xz not found: this test needs the shared test meshes";
  const RecordStats s = check_records(bunny->model(), 16);
  print("bunny", s);
  EXPECT_EQ(s.splits, bunny->model().split_order.size());
  EXPECT_LT(s.bits.total(), full_bits(s));
}

}  // namespace
}  // namespace pms::protocol
