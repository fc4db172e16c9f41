// Split records on hand-made forests: every record round-trips through its own bits, the tables
// round-trip through their serialization, and hostile tables and records fail with pms::Error.
// The real models' round trips and bits per part are in tests/protocol/split_records_test.cpp.
#include <gtest/gtest.h>

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "common/bit_stream.h"
#include "common/error.h"
#include "pm_fixtures.h"
#include "spm/hierarchy.h"
#include "spm/octahedral_normal.h"
#include "spm/split_codec.h"

namespace pms {
namespace {

Hierarchy test_forest() {
  Hierarchy h = test::make_forest(5, [](uint32_t tree, int depth, bool leftmost) {
    return depth < 3 || (depth < 6 && (leftmost || (tree + uint32_t(depth)) % 2 == 0));
  });
  h.compute_ids();
  // Leaves never refine, as a builder's do.
  for (uint32_t n = 0; n < h.node_count(); ++n)
    if (h.is_leaf(n)) h.refine[n].mu = h.refine[n].delta = 0;
  return h;
}

// A forest, its grid positions and its codec.
struct Forest {
  Hierarchy h;
  ModelData model = model_of(h);
  std::vector<uint32_t> q = grid_positions(model, 16);
  SplitCodec codec = SplitCodec::build(model, q, 16);
};
const Forest& forest() {
  static const Forest f{test_forest()};
  return f;
}

struct Encoded {
  BitWriter bits;
  std::vector<uint64_t> start;  // per internal node in split order
};

Encoded encode_all(const SplitCodec& codec, const ModelData& model, const std::vector<uint32_t>& q) {
  Encoded e;
  for (uint32_t node : model.split_order) {
    e.start.push_back(e.bits.size());
    BitWriter w;
    RecordBits parts;
    codec.encode(split_context(model, q, node), split_payload(model, q, node), w, &parts);
    EXPECT_EQ(parts.total(), w.size());
    e.bits.append(w);
  }
  e.start.push_back(e.bits.size());
  return e;
}

TEST(SplitCodec, EveryRecordRoundTripsOnItsOwn) {
  const auto& [h, model, q, codec] = forest();
  const Encoded e = encode_all(codec, model, q);
  ASSERT_GT(model.split_order.size(), 20u);
  for (size_t i = 0; i < model.split_order.size(); ++i) {
    const uint32_t node = model.split_order[i];
    BitReader r(e.bits.bytes(), e.start[i], e.start[i + 1], "record");
    EXPECT_EQ(codec.decode(split_context(model, q, node), r), split_payload(model, q, node)) << "node " << node;
    EXPECT_EQ(r.bits_left(), 0u);
  }
}

TEST(SplitCodec, TablesRoundTripThroughTheirSerialization) {
  const auto& [h, model, q, codec] = forest();
  BitWriter w;
  codec.serialize(w);
  BitReader r(w.bytes(), 0, w.size(), "tables");
  const SplitCodec back = SplitCodec::deserialize(r);
  EXPECT_EQ(back.root_count(), codec.root_count());
  EXPECT_EQ(back.max_depth(), codec.max_depth());
  EXPECT_EQ(back.position_bits(), 16u);
  EXPECT_EQ(encode_all(back, model, q).bits.bytes(), encode_all(codec, model, q).bits.bytes());
  // Every prefix of the tables is refused.
  for (uint64_t end = 0; end < w.size(); end += 7) {
    BitReader cut(w.bytes(), 0, end, "tables");
    EXPECT_THROW(SplitCodec::deserialize(cut), Error) << end;
  }
}

TEST(SplitCodec, TablesWithABadGridStepAreRefused) {
  const auto& [h, model, q, codec] = forest();
  BitWriter w;
  codec.serialize(w);
  // The largest grid step follows u32 root count, u8 depth, u8 position bits and three u16 step ratios.
  constexpr size_t kGridStepAt = 32 + 8 + 8 + 3 * 16;
  for (const float bad : {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(), -1.0f}) {
    BitWriter changed;
    BitReader all(w.bytes(), 0, w.size(), "tables");
    for (size_t i = 0; i < kGridStepAt; ++i) changed.bit(unsigned(all.bits(1, "head")));
    all.bits(32, "grid step");
    changed.bits(std::bit_cast<uint32_t>(bad), 32);
    while (all.bits_left() > 0) changed.bit(unsigned(all.bits(1, "rest")));
    BitReader r(changed.bytes(), 0, changed.size(), "tables");
    EXPECT_THROW(SplitCodec::deserialize(r), Error) << bad;
  }
}

TEST(SplitCodec, TruncatedAndRandomRecordsFailCleanly) {
  const auto& [h, model, q, codec] = forest();
  const Encoded e = encode_all(codec, model, q);
  for (size_t i = 0; i < model.split_order.size(); ++i) {
    const SplitContext context = split_context(model, q, model.split_order[i]);
    for (uint64_t end = e.start[i]; end < e.start[i + 1]; ++end) {
      BitReader r(e.bits.bytes(), e.start[i], end, "record");
      EXPECT_THROW(codec.decode(context, r), Error);
    }
  }
  std::mt19937_64 rng(3);
  size_t decoded = 0, encoded_again = 0;
  for (int trial = 0; trial < 200000; ++trial) {
    std::vector<uint8_t> bytes(1 + rng() % 16);
    for (uint8_t& b : bytes) b = uint8_t(rng());
    const uint32_t node = model.split_order[rng() % model.split_order.size()];
    const SplitContext context = split_context(model, q, node);
    BitReader r(bytes, "random");
    try {
      const SplitPayload p = codec.decode(context, r);
      ++decoded;
      EXPECT_TRUE(is_vertex(p.cut_l) || is_vertex(p.cut_r));
      for (VertexId cut : {p.cut_l, p.cut_r})
        if (is_vertex(cut)) {
          EXPECT_LT(cut.tree, model.root_count);
          EXPECT_FALSE(is_ancestor_or_self(context.vs, cut));
        }
      EXPECT_TRUE(is_canonical(p.info_t) && is_canonical(p.info_u));
      // Cut vertices and position have one coding each: encoding what was read gives the same bits.
      BitWriter again;
      RecordBits parts;
      codec.encode(context, p, again, &parts);
      ++encoded_again;
      BitReader original(bytes, "random"), encoded(again.bytes(), 0, again.size(), "again");
      for (uint64_t bit = 0; bit < parts.topology + parts.geometry; ++bit)
        ASSERT_EQ(original.bits(1, "bit"), encoded.bits(1, "bit")) << "bit " << bit;
    } catch (const Error&) {
    }
  }
  EXPECT_GT(decoded, 0u);  // random bits do form records: the checks above ran
  EXPECT_GT(encoded_again, 0u);
}

TEST(SplitCodec, RandomTablesFailCleanly) {
  std::mt19937_64 rng(5);
  for (int trial = 0; trial < 500; ++trial) {
    std::vector<uint8_t> bytes(rng() % 64);
    for (uint8_t& b : bytes) b = uint8_t(rng());
    if (bytes.size() > 6) bytes[5] = 16;  // a valid position width, to get past the header more often
    BitReader r(bytes, "random tables");
    try {
      SplitCodec::deserialize(r);
    } catch (const Error&) {
    }
  }
}

TEST(SplitCodec, RefusesWhatItCannotCarry) {
  const auto& [h, model, q, codec] = forest();
  const uint32_t node = model.split_order[0];
  const SplitContext context = split_context(model, q, node);
  SplitPayload p = split_payload(model, q, node);
  BitWriter w;
  SplitPayload inside = p;
  inside.cut_l = context.vs.child(0);  // inside v_s's own subtree
  EXPECT_THROW(codec.encode(context, inside, w), Error);
  SplitPayload off_grid = p;
  off_grid.position_t[0] = 1u << 16;
  EXPECT_THROW(codec.encode(context, off_grid, w), Error);
  SplitPayload no_cut = p;
  no_cut.cut_l = no_cut.cut_r = kNoVertex;
  EXPECT_THROW(codec.encode(context, no_cut, w), Error);
  SplitPayload not_sent = p;
  not_sent.info_t.mu = not_sent.info_t.delta = 0;
  not_sent.info_t.radius = 0x3C00;  // never refines, but with a radius: not what as_sent delivers
  EXPECT_THROW(codec.encode(context, not_sent, w), Error);
  EXPECT_THROW(SplitCodec().encode(context, p, w), Error);
}

// The forest with a normal and a color per node: normals all over the sphere (both hemispheres, so steps
// cross the octahedral square's edges), smooth colors with an alpha that jumps.
Hierarchy with_attributes(Hierarchy f) {
  const size_t n = f.node_count();
  f.normals.resize(3 * n);
  f.colors.resize(4 * n);
  for (size_t v = 0; v < n; ++v) {
    const float* p = &f.position[3 * v];
    const float normal[3] = {std::sin(7 * p[0] + 1), std::cos(5 * p[1]), std::sin(3 * p[2] - p[0])};
    const float length = std::sqrt(normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2]);
    for (int k = 0; k < 3; ++k) f.normals[3 * v + size_t(k)] = normal[k] / length;
    for (int k = 0; k < 3; ++k) f.colors[4 * v + size_t(k)] = uint8_t(128 + 127 * std::sin(float(k + 2) * p[k]));
    f.colors[4 * v + 3] = uint8_t(v % 5 ? 255 : 0);
  }
  return f;
}
const Forest& attributed_forest() {
  static const Forest f{with_attributes(test_forest())};
  return f;
}

TEST(SplitCodec, NormalsAndColorsRoundTripThroughRecordsAndTables) {
  const auto& [h, model, q, codec] = attributed_forest();
  ASSERT_TRUE(codec.has_normals() && codec.has_colors());
  BitWriter w;
  codec.serialize(w);
  BitReader r(w.bytes(), 0, w.size(), "tables");
  const SplitCodec back = SplitCodec::deserialize(r);
  ASSERT_TRUE(back.has_normals() && back.has_colors());
  const Encoded e = encode_all(back, model, q);
  EXPECT_EQ(e.bits.bytes(), encode_all(codec, model, q).bits.bytes());
  uint64_t normal_bits = 0, color_bits = 0;
  for (size_t i = 0; i < model.split_order.size(); ++i) {
    const uint32_t node = model.split_order[i];
    const SplitPayload want = split_payload(model, q, node);
    BitReader record(e.bits.bytes(), e.start[i], e.start[i + 1], "record");
    EXPECT_EQ(back.decode(split_context(model, q, node), record), want) << "node " << node;
    uint16_t normal[2];
    encode_normal(&model.normals[3 * size_t(model.first_child[node])], normal);
    EXPECT_EQ(want.normal_t[0], normal[0]);
    EXPECT_EQ(want.normal_t[1], normal[1]);
    BitWriter alone;
    RecordBits parts;
    codec.encode(split_context(model, q, node), want, alone, &parts);
    normal_bits += parts.normal;
    color_bits += parts.color;
  }
  EXPECT_GT(normal_bits, 0u);
  EXPECT_GT(color_bits, 0u);
  // The forest without attributes has no attribute tables.
  EXPECT_FALSE(forest().codec.has_normals() || forest().codec.has_colors());
}

TEST(SplitCodec, RefusesAttributesItCannotCarry) {
  const uint32_t node = forest().model.split_order[0];
  const SplitContext plain_context = split_context(forest().model, forest().q, node);
  BitWriter w;
  SplitPayload with_normal = split_payload(forest().model, forest().q, node);
  with_normal.normal_t[0] = 5;
  EXPECT_THROW(forest().codec.encode(plain_context, with_normal, w), Error) << "a normal in a model without normals";
  SplitPayload with_color = split_payload(forest().model, forest().q, node);
  with_color.color_t[3] = 255;
  EXPECT_THROW(forest().codec.encode(plain_context, with_color, w), Error) << "a color in a model without colors";

  const auto& [h, model, q, codec] = attributed_forest();
  const SplitContext context = split_context(model, q, node);
  // -32768 (decodes as -32767), and edge points whose mirror image is the canonical one.
  for (const std::array<int16_t, 2> bad : {std::array<int16_t, 2>{-32768, 0}, {32767, -9}, {-4, -32767}}) {
    SplitPayload mirror = split_payload(model, q, node);
    mirror.normal_t[0] = uint16_t(bad[0]), mirror.normal_t[1] = uint16_t(bad[1]);
    EXPECT_THROW(codec.encode(context, mirror, w), Error) << bad[0] << ", " << bad[1] << " is not canonical";
  }
}

// Hostile tables may say anything about attributes; hostile records may step off the octahedral square, to
// an edge point's mirror image, or past a color channel's range: refused, and nothing else decodes.
TEST(SplitCodec, HostileAttributeFieldsAreRefused) {
  const auto& [h, model, q, codec] = attributed_forest();
  BitWriter w;
  codec.serialize(w);
  constexpr size_t kAttributesAt = 32 + 8 + 8 + 3 * 16 + 32;  // after the grid step
  std::vector<uint8_t> bytes = w.bytes();
  bytes[kAttributesAt / 8] |= 8;  // an attribute this version does not know (4 is the plain form)
  BitReader unknown(bytes, "tables");
  EXPECT_THROW(SplitCodec::deserialize(unknown), Error);

  std::mt19937_64 rng(11);
  size_t decoded = 0, refused_normal = 0, refused_color = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    std::vector<uint8_t> record(4 + rng() % 24);
    for (uint8_t& b : record) b = uint8_t(rng());
    const SplitContext context = split_context(model, q, model.split_order[rng() % model.split_order.size()]);
    BitReader r(record, "random");
    try {
      const SplitPayload p = codec.decode(context, r);
      ++decoded;
      EXPECT_TRUE(is_canonical_normal(p.normal_t));
    } catch (const Error& e) {
      const std::string what = e.what();
      refused_normal += what.find("normal") != std::string::npos;
      refused_color += what.find("color") != std::string::npos;
    }
  }
  EXPECT_GT(decoded, 0u);
  EXPECT_GT(refused_normal, 0u) << "random records reach the normal's checks";
  EXPECT_GT(refused_color, 0u) << "random records reach the colors' checks";
}

}  // namespace
}  // namespace pms
