// The receiver-driven request code (cheng-ooi §4.3): round trips, the paper's example, its cost on a real
// refinement of bunny, and hostile codes. base64url, its URL form, too.
#include <gtest/gtest.h>
#include <algorithm>
#include <cstdio>

#include "common/camera.h"
#include "protocol/base64url.h"
#include "protocol/message_types.h"
#include "protocol/split_request.h"
#include "protocol_fixtures.h"
#include "spm/adapt.h"
#include "spm/hierarchy.h"
#include "spm/selective_mesh.h"
#include "spm/vertex_hierarchy.h"
#include "spm/vertex_id.h"

namespace pms::test {
namespace {

using protocol::decode_split_request;
using protocol::encode_split_request;
using protocol::ErrorCode;
using protocol::SplitRequest;
using protocol::SplitRequestLimits;

SplitRequestLimits limits_for(uint32_t roots, int max_node_depth) {
  SplitRequestLimits limits;
  limits.root_count = roots;
  limits.max_node_depth = max_node_depth;
  limits.max_ids = 1u << 20;
  limits.max_bytes = 1u << 20;
  return limits;
}

std::vector<VertexId> sorted(std::vector<VertexId> ids) {
  std::sort(ids.begin(), ids.end(), protocol::code_order);
  return ids;
}

TEST(SplitRequest, ThePapersExample) {
  // Figure 6: the two bottom vertices 1010 and 1011 of one tree code as 1011001000; before it, depth 0,
  // one tree and tree id 0 are one '1' bit each.
  const SplitRequest request{0, {{0, 0b1011}, {0, 0b1010}}};
  const std::vector<uint8_t> code = encode_split_request(request);
  EXPECT_EQ(code, (std::vector<uint8_t>{0b11110110, 0b01000000}));
  EXPECT_EQ(decode_split_request(code, limits_for(1, 3)).ids, sorted(request.ids));
}

TEST(SplitRequest, RandomIdSetsRoundTrip) {
  Rng rng(19);
  for (int round = 0; round < 300; ++round) {
    const uint32_t roots = 1 + uint32_t(rng() % 5000);
    const int depth = int(rng() % 40);
    std::vector<VertexId> front = random_front(rng, std::min<uint32_t>(roots, 1 + uint32_t(rng() % 60)), depth);
    // A random subset of a front is an antichain; shift the trees so that deltas vary.
    std::vector<VertexId> ids;
    const uint32_t stride = 1 + uint32_t(rng() % 50);
    for (VertexId v : front)
      if (rng() % 3 && uint64_t(v.tree) * stride < roots) ids.push_back({v.tree * stride, v.node});
    if (ids.empty()) ids.push_back({roots - 1, 1});
    const SplitRequest request{uint32_t(rng() % 9), ids};
    const std::vector<uint8_t> code = encode_split_request(request);
    const SplitRequest back = decode_split_request(code, limits_for(roots, depth));
    EXPECT_EQ(back.depth, request.depth);
    ASSERT_EQ(back.ids, sorted(ids)) << "round " << round;
    EXPECT_EQ(encode_split_request(back), code);  // canonical: the decoded set gives the same bytes
  }
}

TEST(SplitRequest, EncodingIgnoresOrderAndDuplicates) {
  const SplitRequest a{2, {{7, 5}, {3, 4}, {7, 12}, {3, 4}}};
  const SplitRequest b{2, {{3, 4}, {7, 12}, {7, 5}}};
  EXPECT_EQ(encode_split_request(a), encode_split_request(b));
}

TEST(SplitRequest, TheEncoderRefusesWhatIsNotAnAntichain) {
  EXPECT_THROW(encode_split_request({0, {{1, 2}, {1, 9}}}), Error);  // 2 is 9's grandparent
  EXPECT_THROW(encode_split_request({0, {}}), Error);
  EXPECT_THROW(encode_split_request({0, {{1, 0}}}), Error);
}

// Bits per id of `rounds` sent as requests of at most `chunk` ids each, taken in the rounds' order.
double bits_per_id(const std::vector<std::vector<VertexId>>& rounds, size_t chunk, const SplitRequestLimits& limits) {
  uint64_t ids = 0, bits = 0;
  for (const std::vector<VertexId>& round : rounds)
    for (size_t at = 0; at < round.size(); at += chunk) {
      const SplitRequest request{0,
                                 {round.begin() + long(at), round.begin() + long(std::min(round.size(), at + chunk))}};
      const std::vector<uint8_t> code = encode_split_request(request);
      EXPECT_EQ(decode_split_request(code, limits).ids, sorted(request.ids));
      ids += request.ids.size();
      bits += 8 * code.size();
    }
  return double(bits) / double(ids);
}

// A client refining bunny for a close view from its base mesh: each round, the leaves the loop reports
// missing are what a receiver-driven client requests. Sent whole per round, in requests of 64 ids in the
// loop's order, and in requests of 64 in a random order (an importance ranking scatters ids over trees).
TEST(SplitRequest, BitsPerRequestedIdOnACloseViewOfBunny) {
  const BuiltModel* bunny = bunny_model();
  if (!bunny) GTEST_SKIP() << "../shared/models/bunny.ply.xz not found: this test needs the shared test meshes";
  const ModelData model = bunny->model();
  const SplitRequestLimits limits = limits_for(model.root_count, int(max_depth(bunny->hierarchy)) - 1);
  VertexHierarchy hierarchy = VertexHierarchy::from_model(model);
  SelectiveMesh mesh(hierarchy, model.base_faces);
  SelectiveRefinement refinement(mesh, model.scale, AdaptOptions{1.0f});
  const float* lo = model.bbox_min;
  const float* hi = model.bbox_max;
  Camera camera;
  for (int i = 0; i < 3; ++i) camera.target[i] = 0.5f * (lo[i] + hi[i]);
  camera.eye[0] = camera.target[0];
  camera.eye[1] = camera.target[1];
  camera.eye[2] = hi[2] + 0.6f * (hi[1] - lo[1]);  // close in front of the face: part of the model out of view
  refinement.set_view(make_view(camera, lo, hi));
  std::vector<std::vector<VertexId>> rounds;
  refinement.converge([&](std::span<const uint32_t> leaves) {
    std::vector<VertexId> round;
    for (uint32_t slot : leaves)
      if (!model.is_leaf(model.find(hierarchy.id(slot)))) round.push_back(hierarchy.id(slot));
    if (!round.empty()) rounds.push_back(round);
    return add_model_splits(hierarchy, model, leaves);
  });
  size_t ids = 0;
  for (const auto& round : rounds) ids += round.size();
  ASSERT_GT(ids, 1000u);
  const double whole = bits_per_id(rounds, SIZE_MAX, limits);
  const double in_order = bits_per_id(rounds, 64, limits);
  Rng rng(27);
  for (auto& round : rounds) std::shuffle(round.begin(), round.end(), rng);
  const double shuffled = bits_per_id(rounds, 64, limits);
  std::printf(
      "bunny close view: %zu ids in %zu rounds; bits per requested id: %.2f per round, %.2f in requests "
      "of 64, %.2f in requests of 64 in random order\n",
      ids, rounds.size(), whole, in_order, shuffled);
  EXPECT_LE(shuffled, 27.0);  // cheng-ooi §4.3's 27 bits per id, even without locality
  EXPECT_LE(in_order, shuffled);
  EXPECT_LE(whole, in_order);
}

TEST(SplitRequest, HostileCodesAreRejected) {
  const SplitRequestLimits limits = limits_for(100, 10);
  const std::vector<uint8_t> good = encode_split_request({1, {{5, 6}, {5, 7}, {40, 1}, {99, 1024}}});
  ASSERT_NO_THROW(decode_split_request(good, limits));
  for (size_t n = 0; n < good.size(); ++n)  // every truncation
    expect_rejected([&] { decode_split_request({good.data(), n}, limits); }, ErrorCode::bad_message, "split request");
  std::vector<uint8_t> longer = good;
  longer.push_back(0);
  expect_rejected([&] { decode_split_request(longer, limits); }, ErrorCode::bad_message, "after the end");
  std::vector<uint8_t> padded = good;
  padded.back() |= 1;  // the code ends before the last bit, so this is padding or a changed code
  EXPECT_THROW(decode_split_request(padded, limits), protocol::ProtocolError);
  expect_rejected([&] { decode_split_request(good, limits_for(99, 10)); }, ErrorCode::bad_id, "tree 99");
  expect_rejected([&] { decode_split_request(good, limits_for(100, 9)); }, ErrorCode::bad_id, "depth 10");
  SplitRequestLimits few = limits;
  few.max_ids = 3;
  expect_rejected([&] { decode_split_request(good, few); }, ErrorCode::too_large, "more than 3 ids");
  few = limits;
  few.max_depth = 0;
  expect_rejected([&] { decode_split_request(good, few); }, ErrorCode::bad_message, "depth");
  few = limits;
  few.max_bytes = good.size() - 1;
  expect_rejected([&] { decode_split_request(good, few); }, ErrorCode::too_large, "bytes");
  const std::vector<uint8_t> zeros(64, 0);  // an Exp-Golomb prefix that never ends
  expect_rejected([&] { decode_split_request(zeros, limits); }, ErrorCode::bad_message, "over 32 bits");
  const std::vector<uint8_t> ones(64, 0xFF);  // a path that only goes left, deeper than the model
  expect_rejected([&] { decode_split_request(ones, limits); }, ErrorCode::bad_id, "deepest split");
  SplitRequestLimits none = limits;
  none.max_node_depth = -1;  // a model without splits
  expect_rejected(
      [&] {
        decode_split_request(encode_split_request({0, {{0, 1}}}), none);
      },
      ErrorCode::bad_id, "depth 0");
}

TEST(Base64url, RoundTripsAndIsStrict) {
  Rng rng(7);
  for (int n = 0; n < 40; ++n) {
    std::vector<uint8_t> bytes(static_cast<size_t>(n));
    for (uint8_t& b : bytes) b = uint8_t(rng());
    const std::string text = protocol::base64url_encode(bytes);
    EXPECT_EQ(text.find_first_of("+/="), std::string::npos);
    EXPECT_EQ(protocol::base64url_decode(text), bytes);
  }
  EXPECT_EQ(protocol::base64url_encode(std::vector<uint8_t>{0xFB, 0xFF}), "-_8");
  EXPECT_FALSE(protocol::base64url_decode("-_9"));    // non-zero bits after the last byte
  EXPECT_FALSE(protocol::base64url_decode("AAAA="));  // padding
  EXPECT_FALSE(protocol::base64url_decode("AA+A"));   // not the URL alphabet
  EXPECT_FALSE(protocol::base64url_decode("AAAAA"));  // 1 mod 4
}

}  // namespace
}  // namespace pms::test
