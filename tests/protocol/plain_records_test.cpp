// The plain record form (spm/split_codec.h, RecordForm::plain; docs/protocol.md, "The plain form"): records
// without the children's refinement info, derived from the same model as the info form. Every plain record
// of the bunny and the sphere (normals, colors) round-trips, the plain records are shorter than the info
// ones, whole-tree bands give a client the model's shape and positions, the encoder refuses to put info in
// the plain form and the decoders refuse tables with unknown bits and records that are not plain.
#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "common/bit_stream.h"
#include "common/error.h"
#include "protocol/position_grid.h"
#include "protocol/split_bands.h"
#include "protocol_fixtures.h"
#include "spm/hierarchy.h"
#include "spm/refine_info.h"
#include "spm/split_codec.h"
#include "spm/vertex_hierarchy.h"

namespace pms::protocol {
namespace {

constexpr uint32_t kPositionBits = 16;
constexpr uint32_t kMany = 1u << 24;

struct Forms {
  ModelData model;
  std::vector<uint32_t> q;
  EncodedRecords info, plain;
  SplitCodec plain_codec;
};

Forms forms_of(const ModelData& model) {
  Forms f{model,
          grid_positions(model, kPositionBits),
          encode_records(model, kPositionBits),
          encode_records(model, kPositionBits, RecordForm::plain),
          {}};
  BitReader r(f.plain.tables, "plain tables");
  f.plain_codec = SplitCodec::deserialize(r);
  return f;
}

// What a plain record of `node` says: its split with the children's info replaced by their presence.
SplitPayload plain_split(const ModelData& model, const std::vector<uint32_t>& q, uint32_t node) {
  const uint32_t t = model.first_child[node];
  return plain_payload(split_payload(model, q, node), !model.is_leaf(t), !model.is_leaf(t + 1));
}

void expect_round_trip_and_shorter(const ModelData& model) {
  const Forms f = forms_of(model);
  EXPECT_EQ(f.plain_codec.form(), RecordForm::plain);
  for (uint32_t node : f.model.split_order) {
    BitReader r(f.plain.records, f.plain.offsets[node], f.plain.offsets[node + 1], "plain record");
    ASSERT_EQ(f.plain_codec.decode(split_context(f.model, f.q, node), r), plain_split(f.model, f.q, node))
        << "node " << node;
    EXPECT_EQ(r.bits_left(), 0u);
  }
  const uint64_t info_bits = f.info.offsets.back(), plain_bits = f.plain.offsets.back();
  std::printf("%zu splits: info form %.1f bits a split, plain form %.1f (tables %zu and %zu bytes)\n",
              f.model.split_order.size(), double(info_bits) / double(f.model.split_order.size()),
              double(plain_bits) / double(f.model.split_order.size()), f.info.tables.size(), f.plain.tables.size());
  EXPECT_LT(plain_bits, info_bits);
  EXPECT_LT(f.plain.tables.size(), f.info.tables.size());
}

TEST(PlainRecords, EveryBunnyRecordRoundTripsAndIsShorterThanWithInfo) {
  const test::BuiltModel* bunny = test::bunny_model();
  if (!bunny) GTEST_SKIP() << "../shared/models/bunny.ply.xz is absent";
  expect_round_trip_and_shorter(bunny->model());
}

TEST(PlainRecords, NormalsAndColorsRoundTripInThePlainForm) {
  expect_round_trip_and_shorter(test::sphere_model().model());
}

TEST(PlainRecords, WholeTreeBandsGiveTheClientTheModelsShapeAndPositions) {
  const Forms f = forms_of(test::terrain_model().model());
  const PositionGrid grid = model_grid(f.model, kPositionBits);
  VertexHierarchy h;
  for (uint32_t r = 0; r < f.model.root_count; ++r) {
    float p[3];
    snap_position(grid, &f.model.position[3 * size_t(r)], p);
    h.add_root(f.model.id(r), p, f.model.is_leaf(r) ? as_sent(RefineInfo{}) : plain_split_info());
  }
  SplitRequest request{64, {}};
  for (uint32_t r = 0; r < f.model.root_count; ++r)
    if (!f.model.is_leaf(r)) request.ids.push_back(f.model.id(r));
  BitWriter w;
  const StoredRecords plain{f.plain.records, f.plain.offsets, RecordForm::plain};
  for (VertexId id : request.ids) write_split_band(f.model, plain, f.model.find(id), request.depth, w);
  EXPECT_EQ(read_split_bands(w.bytes(), request, f.plain_codec, grid, h, kMany), f.model.split_order.size());
  for (uint32_t n = 0; n < f.model.node_count(); ++n) {
    const uint32_t slot = h.find(f.model.id(n));
    ASSERT_NE(slot, kNone) << to_string(f.model.id(n));
    EXPECT_EQ(h.is_leaf(slot), f.model.is_leaf(n));
    EXPECT_EQ(never_refines(h.refine(slot)), f.model.is_leaf(n)) << "a plain child says whether it has a split";
    float p[3];
    snap_position(grid, &f.model.position[3 * size_t(n)], p);
    for (int k = 0; k < 3; ++k) EXPECT_EQ(h.position(slot)[k], p[k]);
  }
}

TEST(PlainRecords, TheEncoderRefusesRefinementInfoInThePlainForm) {
  const Forms f = forms_of(test::terrain_model().model());
  size_t refused = 0;
  for (uint32_t node : f.model.split_order) {
    const SplitPayload with_info = split_payload(f.model, f.q, node);
    if (with_info == plain_split(f.model, f.q, node)) continue;
    BitWriter w;
    EXPECT_THROW(f.plain_codec.encode(split_context(f.model, f.q, node), with_info, w), Error);
    ++refused;
  }
  EXPECT_GT(refused, 0u);
}

TEST(PlainRecords, TablesWithUnknownAttributeBitsAreRefused) {
  const Forms f = forms_of(test::terrain_model().model());
  constexpr size_t kAttributesAt = 32 + 8 + 8 + 3 * 16 + 32;  // after the grid step
  for (const uint8_t unknown : {8, 16, 32, 64, 128}) {
    std::vector<uint8_t> bytes = f.plain.tables;
    bytes[kAttributesAt / 8] |= unknown;
    BitReader r(bytes, "tables");
    EXPECT_THROW(SplitCodec::deserialize(r), Error) << int(unknown);
  }
}

TEST(PlainRecords, HostilePlainRecordsDecodeToPlainSplitsOrFail) {
  const Forms f = forms_of(test::terrain_model().model());
  std::mt19937_64 rng(46);
  size_t decoded = 0, refused = 0;
  for (int trial = 0; trial < 50000; ++trial) {
    std::vector<uint8_t> bytes(1 + rng() % 12);
    for (uint8_t& b : bytes) b = uint8_t(rng());
    const uint32_t node = f.model.split_order[rng() % f.model.split_order.size()];
    const SplitContext context = split_context(f.model, f.q, node);
    BitReader r(bytes, "random");
    try {
      const SplitPayload p = f.plain_codec.decode(context, r);
      ++decoded;
      // Nothing but presence: a decoded record is a plain one, and the plain encoder takes it back.
      EXPECT_EQ(p, plain_payload(p, !never_refines(p.info_t), !never_refines(p.info_u)));
      BitWriter again;
      f.plain_codec.encode(context, p, again);
    } catch (const Error&) {
      ++refused;
    }
  }
  EXPECT_GT(decoded, 0u);
  EXPECT_GT(refused, 0u);
  // Truncated plain records fail.
  const uint32_t node = f.model.split_order.front();
  for (uint64_t end = f.plain.offsets[node]; end < f.plain.offsets[node + 1]; ++end) {
    BitReader r(f.plain.records, f.plain.offsets[node], end, "truncated");
    EXPECT_THROW(f.plain_codec.decode(split_context(f.model, f.q, node), r), Error);
  }
}

}  // namespace
}  // namespace pms::protocol
