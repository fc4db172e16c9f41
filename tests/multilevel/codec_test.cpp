// Compressed multilevel levels (multilevel/codec.h): every level of a build decodes, by addLevel,
// into exactly the structure with its positions on the grid; hostile compressed levels are refused by name.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <string>

#include "common/error.h"
#include "error_of.h"
#include "expect.h"
#include "fixtures/view_models.h"
#include "multilevel/build.h"
#include "multilevel/codec.h"
#include "multilevel/file.h"
#include "multilevel/loader.h"

namespace pms {
namespace {

using test::error_of;

const auto expect_same = test::expect_same_multilevel;

// Loads every compressed level through addLevel, checking after each that the loaded levels are the
// snapped mesh's, and returns the whole structure.
MultilevelMesh load_compressed(const MultilevelMesh& m, uint32_t bits) {
  const MultilevelParts parts = multilevel_compressed_parts(m, bits);
  const MultilevelMesh snapped = snapped_multilevel(m, bits);
  MultilevelLoader loader("test", parts.head, {}, MultilevelForm::compressed);
  for (const auto& level : parts.levels) {
    loader.add_level("test", level);
    const uint32_t n = loader.mesh().vertices(), d = m.dimension;
    EXPECT_EQ(n, snapped.vertex_count[loader.finest_loaded()]);
    EXPECT_TRUE(std::equal(loader.mesh().positions.begin(), loader.mesh().positions.end(), snapped.positions.begin(),
                           snapped.positions.begin() + size_t(n) * d))
        << "level " << loader.finest_loaded();
  }
  EXPECT_TRUE(loader.complete());
  return loader.release();
}

TEST(MultilevelCodec, EveryLevelOfBunnyDecodesToTheStructureOnTheGrid) {
  const test::BuiltModel* bunny = test::built_bunny();
  if (!bunny) GTEST_SKIP() << "../shared/models/bunny.ply.xz not found: this test needs the shared test meshes";
  const MultilevelMesh m = build_multilevel(bunny->input, collapses_of(bunny->h));
  ASSERT_GT(m.level_count(), 50u);
  const MultilevelMesh got = load_compressed(m, kDefaultPositionBits);
  expect_same(got, snapped_multilevel(m, kDefaultPositionBits));
  // On the grid: within half a step of the input on every axis, and snapping again changes nothing.
  const PositionGrid grid = multilevel_grid(m, kDefaultPositionBits);
  for (size_t i = 0; i < m.positions.size(); ++i)
    ASSERT_LE(std::abs(got.positions[i] - m.positions[i]), position_error_bound(grid, int(i % 3))) << i;
  expect_same(snapped_multilevel(got, kDefaultPositionBits), got);
}

// What the compressed levels code best: within a level, the triangles by the vertex of the level each
// stands on in its LOD, each starting at a corner that reaches that vertex.
TEST(MultilevelCodec, BuildsOrderEachLevelsTrianglesByTheVertexTheyStandOn) {
  const test::BuiltModel& terrain = test::built_terrain();
  const MultilevelMesh m = build_multilevel(terrain.input, collapses_of(terrain.h));
  uint64_t standing = 0;
  for (uint32_t level = 0; level < m.level_count(); ++level) {
    const uint32_t n_l = m.vertex_count[level], lo = n_l - m.level_vertices(level);
    uint32_t last = 0;
    bool past_standing = false;  // the triangles that stand on no vertex of the level come last
    for (uint32_t t = m.triangle_count[level] - m.level_triangles(level); t < m.triangle_count[level]; ++t) {
      uint32_t x = m.triangles[3 * size_t(t)];
      while (x != MultilevelMesh::kNoRepresentative && x >= n_l) x = m.representative[x];
      if (x == MultilevelMesh::kNoRepresentative || x < lo) {
        past_standing = true;
        continue;
      }
      ASSERT_FALSE(past_standing) << "level " << level << ", triangle " << t;
      ASSERT_GE(x, last) << "level " << level << ", triangle " << t;
      last = x;
      ++standing;
    }
  }
  EXPECT_GT(standing, uint64_t(m.faces()) / 2);
}

TEST(MultilevelCodec, MergedLevelsAttributesAndCoarseGridsRoundTrip) {
  const test::BuiltModel& terrain = test::built_terrain();
  for (uint32_t levels : {1u, 4u, 10u})
    for (uint32_t bits : {1u, 8u, 24u}) {
      MultilevelMesh m = build_multilevel(terrain.input, collapses_of(terrain.h), levels);
      m.normals.assign(size_t(m.vertices()) * 3, 0.0f);
      m.colors.assign(size_t(m.vertices()) * 4, 0);
      for (size_t i = 0; i < m.normals.size(); ++i) m.normals[i] = float(i % 7) / 7;
      for (size_t i = 0; i < m.colors.size(); ++i) m.colors[i] = uint8_t(i * 31);
      expect_same(load_compressed(m, bits), snapped_multilevel(m, bits));
    }
}

TEST(MultilevelCodec, PaperFigureSixIn2dRoundTrips) {
  MultilevelMesh m;  // Fig. 6's structure, 2D
  m.dimension = 2;
  m.positions = {-3, 3, 3, 3, -3, -3, 3, -3, -2.3f, 3, -3, 2.3f, 2.3f, 2.3f, 2.3f, 3, 2.3f, 2.3f, 3, 2.3f};
  m.triangles = {6, 2, 8, 3, 8, 2, 4, 6, 7, 5, 2, 6, 6, 4, 5, 4, 0, 5, 8, 3, 9, 9, 1, 8, 7, 8, 1, 8, 7, 6};
  m.representative = {MultilevelMesh::kNoRepresentative,
                      MultilevelMesh::kNoRepresentative,
                      MultilevelMesh::kNoRepresentative,
                      MultilevelMesh::kNoRepresentative,
                      0,
                      2,
                      0,
                      1,
                      1,
                      3};
  m.representative[4] = 0;
  m.vertex_count = {10, 7, 4};
  m.triangle_count = {10, 6, 2};
  validate_multilevel("fig6", m);
  expect_same(load_compressed(m, 12), snapped_multilevel(m, 12));
}

TEST(MultilevelCodec, HostileCompressedPiecesAreRefusedByName) {
  const test::BuiltModel& terrain = test::built_terrain();
  const MultilevelMesh m = build_multilevel(terrain.input, collapses_of(terrain.h), 6);
  const MultilevelParts parts = multilevel_compressed_parts(m);
  const auto compressed = MultilevelForm::compressed;
  EXPECT_EQ(error_of([&] { MultilevelLoader("h", std::span(parts.head).first(32), {}, compressed); }),
            "h: compressed head: 32 bytes (64 expected)");
  std::vector<uint8_t> head = parts.head;
  head[32] = 30;  // position bits
  EXPECT_EQ(error_of([&] { MultilevelLoader("h", head, {}, compressed); }),
            "h: compressed head: 30 position bits (1 to 24)");
  head = parts.head;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::memcpy(head.data() + 36, &nan, 4);
  EXPECT_EQ(error_of([&] { MultilevelLoader("h", head, {}, compressed); }),
            "h: compressed head: the grid's box is not a box");

  // A head of another version of the compressed levels (HEAD's reserved word), e.g. one cached before it.
  head = parts.head;
  std::memset(head.data() + 28, 0, 4);
  EXPECT_EQ(error_of([&] { MultilevelLoader("h", head, {}, compressed); }),
            "h: compressed head: version 0 levels (this client decodes version 2); load the model again");

  // A level out of order, truncated, longer than its stream, or with counts past the head's totals.
  MultilevelLoader out_of_order("h", parts.head, {}, compressed);
  EXPECT_EQ(error_of([&] { out_of_order.add_level("GET /l", parts.levels[1]); }),
            "GET /l: compressed level 5: says it is level 4");
  const std::vector<uint8_t>& first = parts.levels[0];
  for (size_t cut : {size_t(0), size_t(3), size_t(17), first.size() / 2, first.size() - 1}) {
    MultilevelLoader truncated("h", parts.head, {}, compressed);
    const std::string e = error_of([&] { truncated.add_level("GET /l", std::span(first).first(cut)); });
    EXPECT_EQ(e.rfind("GET /l: ", 0), 0u) << e;
    EXPECT_NE(e.find("truncated"), std::string::npos) << "cut at " << cut << ": " << e;
  }
  std::vector<uint8_t> longer = first;
  longer.push_back(0);
  MultilevelLoader trailing("h", parts.head, {}, compressed);
  EXPECT_EQ(error_of([&] { trailing.add_level("GET /l", longer); }),
            "GET /l: compressed level 5: 1 byte after the stream's end");
  std::vector<uint8_t> inflated = first;
  inflated[4] = 0xFF, inflated[5] = 0xFF, inflated[6] = 0xFF;  // vertex count
  MultilevelLoader too_many("h", parts.head, {}, compressed);
  EXPECT_EQ(error_of([&] { too_many.add_level("GET /l", inflated); }),
            "GET /l: compressed level 5: more vertices, triangles or representatives than the head's totals leave");

  // Every byte of every level changed in turn either decodes to a structure the loader accepts or is
  // refused with an error naming the resource: never a crash, never silence about a broken structure.
  for (size_t i = 0; i < parts.levels.size(); ++i)
    for (size_t at = 0; at < parts.levels[i].size(); at += 1 + parts.levels[i].size() / 64) {
      MultilevelLoader loader("h", parts.head, {}, compressed);
      for (size_t j = 0; j < i; ++j) loader.add_level("GET /l", parts.levels[j]);
      std::vector<uint8_t> bad = parts.levels[i];
      bad[at] ^= 0x5A;
      const std::string e = error_of([&] { loader.add_level("GET /l", bad); });
      if (!e.empty()) {
        EXPECT_EQ(e.rfind("GET /l: ", 0), 0u) << e;
      }
    }
}

}  // namespace
}  // namespace pms
