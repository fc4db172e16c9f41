// Records format 3 (protocol/split_bands.h): bands written from a model's stored records and read by a
// client that holds only the base mesh end with every node of the model at the values every mode
// evaluates; what the client already holds is skipped; a body that is not one is an error, never a guess.
#include <gtest/gtest.h>

#include <vector>

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

struct Stored {
  ModelData model;  // a view: cheap to copy
  PositionGrid grid;
  EncodedRecords encoded;
  SplitCodec codec;
  StoredRecords records() const { return {encoded.records, encoded.offsets}; }
};

Stored stored(const ModelData& model) {
  Stored s{model, model_grid(model, kPositionBits), encode_records(model, kPositionBits), {}};
  BitReader r(s.encoded.tables, "tables");
  s.codec = SplitCodec::deserialize(r);
  return s;
}

// The client's hierarchy after BASE: the roots at their snapped positions, infos as sent.
VertexHierarchy base_hierarchy(const Stored& s) {
  VertexHierarchy h;
  for (uint32_t r = 0; r < s.model.root_count; ++r) {
    float p[3];
    snap_position(s.grid, &s.model.position[3 * size_t(r)], p);
    h.add_root(s.model.id(r), p, as_sent(s.model.refine[r]));
  }
  return h;
}

std::vector<uint8_t> bands(const Stored& s, const SplitRequest& request) {
  BitWriter w;
  for (VertexId id : request.ids) write_split_band(s.model, s.records(), s.model.find(id), request.depth, w);
  return w.bytes();
}

// Every split root of the model, whole trees deep.
SplitRequest whole_model(const ModelData& model) {
  SplitRequest request{64, {}};
  for (uint32_t r = 0; r < model.root_count; ++r)
    if (!model.is_leaf(r)) request.ids.push_back(model.id(r));
  return request;
}

TEST(SplitBands, WholeTreesGiveTheClientEveryNodeAtTheSentValues) {
  const Stored s = stored(test::terrain_model().model());
  VertexHierarchy h = base_hierarchy(s);
  const SplitRequest request = whole_model(s.model);
  const uint32_t added = read_split_bands(bands(s, request), request, s.codec, s.grid, h, kMany);
  EXPECT_EQ(added, s.model.split_order.size());
  for (uint32_t n = 0; n < s.model.node_count(); ++n) {
    const uint32_t slot = h.find(s.model.id(n));
    ASSERT_NE(slot, kNone) << to_string(s.model.id(n));
    float p[3];
    snap_position(s.grid, &s.model.position[3 * size_t(n)], p);
    for (int k = 0; k < 3; ++k) EXPECT_EQ(h.position(slot)[k], p[k]);
    EXPECT_EQ(h.refine(slot), as_sent(s.model.refine[n]));
    EXPECT_EQ(h.is_leaf(slot), s.model.is_leaf(n));
  }
}

TEST(SplitBands, SplitsAlreadyHeldAreSkippedAndTheirDescendantsStillRead) {
  const Stored s = stored(test::terrain_model().model());
  VertexHierarchy h = base_hierarchy(s);
  SplitRequest shallow = whole_model(s.model);
  shallow.depth = 1;
  const uint32_t first = read_split_bands(bands(s, shallow), shallow, s.codec, s.grid, h, kMany);
  EXPECT_GT(first, shallow.ids.size());
  const SplitRequest deep = whole_model(s.model);
  const uint32_t rest = read_split_bands(bands(s, deep), deep, s.codec, s.grid, h, kMany);
  EXPECT_EQ(first + rest, s.model.split_order.size());
}

TEST(SplitBands, ABodyThatIsNotOneIsAnError) {
  const Stored s = stored(test::terrain_model().model());
  SplitRequest request = whole_model(s.model);
  request.ids.resize(4);
  request.depth = 3;
  const std::vector<uint8_t> body = bands(s, request);
  auto read = [&](const std::vector<uint8_t>& bytes, const SplitRequest& r, uint32_t max = kMany) {
    VertexHierarchy h = base_hierarchy(s);
    return read_split_bands(bytes, r, s.codec, s.grid, h, max);
  };
  EXPECT_GT(read(body, request), 0u);
  std::vector<uint8_t> truncated(body.begin(), body.end() - 1);
  EXPECT_THROW(read(truncated, request), Error);
  std::vector<uint8_t> longer = body;
  longer.push_back(0);
  EXPECT_THROW(read(longer, request), Error) << "a byte past the last record";
  EXPECT_THROW(read(body, request, 3), Error) << "over the record limit";
  SplitRequest unknown = request;
  unknown.ids[0] = unknown.ids[0].child(0).child(0);  // a node the base mesh does not hold
  EXPECT_THROW(read(body, unknown), Error);
  // Flipped bits decode to an error or to some other valid splits, never past the body.
  for (size_t i = 0; i < body.size(); i += 7) {
    std::vector<uint8_t> flipped = body;
    flipped[i] ^= 0x5A;
    try {
      read(flipped, request);
    } catch (const Error&) {
    }
  }
}

}  // namespace
}  // namespace pms::protocol
