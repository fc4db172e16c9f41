// Texture coordinates through the multilevel structure (gueziec et al. 1999, Fig. 9: "texture coordinates
// are specified for each vertex"): builds from collapses and from clusterings carry them, every LOD and
// geomorph has them, and the binary and compressed forms keep them (the compressed one on its own grid).
// The inputs' texture coordinates are an affine function of position (a planar projection), so a vertex
// carries the right ones iff they are that function of its position, also halfway through a geomorph.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include "common/error.h"
#include "error_of.h"
#include "expect.h"
#include "fixtures/view_models.h"
#include "multilevel/build.h"
#include "multilevel/cluster.h"
#include "multilevel/codec.h"
#include "multilevel/file.h"
#include "multilevel/loader.h"

namespace pms {
namespace {

using test::error_of;

// u, v: x and y over the box's x and y extent, shifted (so that the texcoord box is not the unit square).
struct Projection {
  float lo[2], scale[2];
  explicit Projection(const std::vector<float>& positions) {
    float hi[2];
    for (int k = 0; k < 2; ++k) lo[k] = hi[k] = positions[k];
    for (size_t i = 0; i < positions.size(); i += 3)
      for (int k = 0; k < 2; ++k) lo[k] = std::min(lo[k], positions[i + k]), hi[k] = std::max(hi[k], positions[i + k]);
    for (int k = 0; k < 2; ++k) scale[k] = 1.0f / (hi[k] - lo[k]);
  }
  float at(const float* p, int k) const { return (p[k] - lo[k]) * scale[k] + 0.25f * float(k); }
};

Mesh textured(const Mesh& input) {
  Mesh mesh = input;
  const Projection f(mesh.positions);
  mesh.texcoords.resize(mesh.vertex_count() * 2);
  for (size_t v = 0; v < mesh.vertex_count(); ++v)
    for (int k = 0; k < 2; ++k) mesh.texcoords[2 * v + k] = f.at(&mesh.positions[3 * v], k);
  return mesh;
}

// Every vertex of `lod` carries the projection of its position: exactly, or within `tolerance` (a geomorph
// blends both linearly, so they stay in step up to rounding). Returns how many vertices are not exact.
size_t expect_projected(const Projection& f, const Mesh& lod, float tolerance, const std::string& what) {
  EXPECT_EQ(lod.texcoords.size(), 2 * lod.vertex_count()) << what;
  size_t inexact = 0;
  for (size_t v = 0; v < lod.vertex_count() && 2 * v + 1 < lod.texcoords.size(); ++v)
    for (int k = 0; k < 2; ++k) {
      const float want = f.at(&lod.positions[3 * v], k), got = lod.texcoords[2 * v + k];
      inexact += got != want;
      if (tolerance == 0) EXPECT_EQ(got, want) << what << ": vertex " << v;
      else EXPECT_NEAR(got, want, tolerance) << what << ": vertex " << v;
    }
  return inexact;
}

const Mesh& textured_bunny_or_terrain(const test::BuiltModel*& model) {
  model = test::built_bunny();
  if (!model) model = &test::built_terrain();
  static const Mesh mesh = textured(model->input);
  return mesh;
}

TEST(MultilevelTexcoords, EveryLevelAndAGeomorphCarryThem) {
  const test::BuiltModel* model = nullptr;
  const Mesh& input = textured_bunny_or_terrain(model);
  const Projection f(input.positions);
  const MultilevelMesh m = build_multilevel(input, collapses_of(model->h), 8);
  ASSERT_EQ(m.texcoords.size(), 2 * size_t(m.vertices()));
  MultilevelLod lod(m);
  lod.set_level(0u);
  const Mesh finest = lod_mesh(m, lod);
  // Level 0 is the input: the same (position, texcoord) pairs.
  std::vector<std::array<float, 5>> got, want;
  for (size_t v = 0; v < finest.vertex_count(); ++v)
    got.push_back({finest.positions[3 * v], finest.positions[3 * v + 1], finest.positions[3 * v + 2],
                   finest.texcoords[2 * v], finest.texcoords[2 * v + 1]});
  for (size_t v = 0; v < input.vertex_count(); ++v)
    want.push_back({input.positions[3 * v], input.positions[3 * v + 1], input.positions[3 * v + 2],
                    input.texcoords[2 * v], input.texcoords[2 * v + 1]});
  std::sort(got.begin(), got.end());
  std::sort(want.begin(), want.end());
  EXPECT_EQ(got, want);
  for (uint32_t l = 0; l < m.level_count(); ++l) {
    lod.set_level(l);
    expect_projected(f, lod_mesh(m, lod), 0, "level " + std::to_string(l));
  }
  // Halfway from level 2 to level 1: the level-1 vertices move and their texture coordinates with them;
  // the coarser vertices keep theirs exactly.
  lod.set_level(1.5f);
  const Mesh morph = lod_mesh(m, lod);
  EXPECT_GT(expect_projected(f, morph, 1e-5f, "geomorph 1.5"), 0u) << "nothing was blended";
  for (size_t i = 0; i < 2 * size_t(m.vertex_count[2]); ++i) ASSERT_EQ(morph.texcoords[i], m.texcoords[i]) << i;
  // t = 0.5 is the mean of the vertex's own and where it stands at level 2.
  lod.set_level(2u);
  const Mesh coarse = lod_mesh(m, lod);
  size_t checked = 0;
  for (uint32_t v = m.vertex_count[2]; v < m.vertex_count[1]; ++v) {
    uint32_t at = m.representative[v];
    while (at != MultilevelMesh::kNoRepresentative && at >= m.vertex_count[2]) at = m.representative[at];
    if (at == MultilevelMesh::kNoRepresentative) continue;
    for (int k = 0; k < 2; ++k)
      ASSERT_FLOAT_EQ(morph.texcoords[2 * size_t(v) + k],
                      0.5f * coarse.texcoords[2 * size_t(at) + k] + 0.5f * m.texcoords[2 * size_t(v) + k]);
    ++checked;
  }
  EXPECT_GT(checked, 0u);
}

TEST(MultilevelTexcoords, ClusteringsKeepThePreferredAncestorsTexcoords) {
  const Mesh input = textured(test::built_terrain().input);
  const Projection f(input.positions);
  const std::vector<uint32_t> grids = {32, 8, 2};
  const MultilevelMesh m = build_multilevel_from_clusterings(input, grid_clusterings(input, grids));
  ASSERT_EQ(m.level_count(), 4u);
  MultilevelLod lod(m);
  for (uint32_t l = 0; l < m.level_count(); ++l) {
    lod.set_level(l);
    // The secondary array moves a clustered LOD's vertices to their clusters; their texture coordinates
    // stay their own (a cluster may span charts), the projection of their own positions.
    Mesh own = lod_mesh(m, lod);
    std::copy_n(m.positions.begin(), own.positions.size(), own.positions.begin());
    expect_projected(f, own, 0, "clustering level " + std::to_string(l));
  }
}

TEST(MultilevelTexcoords, BinaryRoundTripIsExactAndCostsEightBytesAVertex) {
  const test::BuiltModel& terrain = test::built_terrain();
  const Mesh input = textured(terrain.input);
  const MultilevelMesh m = build_multilevel(input, collapses_of(terrain.h), 6);
  const std::vector<uint8_t> bytes = format_multilevel_binary(m);
  const MultilevelMesh back = parse_multilevel_binary("t", bytes);
  test::expect_same_multilevel(back, m);
  MultilevelMesh plain = m;
  plain.texcoords.clear();
  const std::vector<uint8_t> without = format_multilevel_binary(plain);
  EXPECT_EQ(bytes.size(),
            without.size() + 8 * size_t(m.vertices()));  // each LEVL grows by 8 bytes a vertex, all 8-aligned
  EXPECT_TRUE(parse_multilevel_binary("t", without).texcoords.empty());
  // The ASCII form has no place for them (Fig. 6 "doesn't show this"): they are left out.
  EXPECT_TRUE(parse_multilevel_ascii("t", format_multilevel_ascii(m)).texcoords.empty());
  // Like positions and normals, they must be finite: the writer refuses them, and so does the reader of a
  // file whose first vertex's (in the coarsest level's section) were made NaN and resealed.
  MultilevelMesh broken = m;
  broken.texcoords[5] = std::nanf("");
  EXPECT_NE(error_of([&] { format_multilevel_binary(broken); }).find("texture coordinate is not finite"),
            std::string::npos);
  std::vector<uint8_t> hostile = bytes;
  const auto first = std::search(hostile.begin(), hostile.end(), reinterpret_cast<const uint8_t*>(&m.texcoords[0]),
                                 reinterpret_cast<const uint8_t*>(&m.texcoords[0]) + 8);
  ASSERT_NE(first, hostile.end());
  const float nan = std::nanf("");
  std::memcpy(&*first, &nan, 4);
  reseal_multilevel_binary(hostile);
  EXPECT_NE(error_of([&] {
              parse_multilevel_binary("t", hostile);
            }).find("a vertex texture coordinate of level 5 is not finite"),
            std::string::npos);
}

// Loads every compressed level and returns the whole structure.
MultilevelMesh load_compressed(const MultilevelParts& parts) {
  MultilevelLoader loader("test", parts.head, {}, MultilevelForm::compressed);
  for (const auto& level : parts.levels) loader.add_level("test", level);
  EXPECT_TRUE(loader.complete());
  return loader.release();
}

TEST(MultilevelTexcoords, CompressedRoundTripIsOnTheirGrid) {
  const test::BuiltModel& terrain = test::built_terrain();
  const MultilevelMesh m = build_multilevel(textured(terrain.input), collapses_of(terrain.h), 6);
  for (uint32_t bits : {4u, 12u, 16u}) {
    const MultilevelParts parts = multilevel_compressed_parts(m, kDefaultPositionBits, nullptr, bits);
    ASSERT_EQ(parts.head.size(), 80u);
    const MultilevelMesh got = load_compressed(parts);
    test::expect_same_multilevel(got, snapped_multilevel(m, kDefaultPositionBits, bits));
    const PositionGrid grid = multilevel_texcoord_grid(m, bits);
    ASSERT_EQ(got.texcoords.size(), m.texcoords.size());
    for (size_t i = 0; i < m.texcoords.size(); ++i)
      ASSERT_LE(std::abs(got.texcoords[i] - m.texcoords[i]), position_error_bound(grid, int(i % 2)))
          << bits << " bits, " << i;
  }
  // Without texture coordinates the compressed form carries none: a 64-byte head and the same levels.
  MultilevelMesh plain = m;
  plain.texcoords.clear();
  const MultilevelParts without = multilevel_compressed_parts(plain), with = multilevel_compressed_parts(m);
  EXPECT_EQ(without.head.size(), 64u);
  uint64_t saved = 0;
  for (size_t i = 0; i < with.levels.size(); ++i) saved += with.levels[i].size() - without.levels[i].size();
  EXPECT_GT(saved, 0u);
  EXPECT_LT(saved, 4 * uint64_t(m.vertices()))
      << "16-bit texture coordinates predicted from representatives: under 4 bytes a vertex";
}

TEST(MultilevelTexcoords, HostileCompressedHeadsAreRefused) {
  const test::BuiltModel& terrain = test::built_terrain();
  const MultilevelMesh m = build_multilevel(textured(terrain.input), collapses_of(terrain.h), 6);
  const MultilevelParts parts = multilevel_compressed_parts(m);
  const auto compressed = MultilevelForm::compressed;
  EXPECT_EQ(error_of([&] { MultilevelLoader("h", std::span(parts.head).first(64), {}, compressed); }),
            "h: compressed head: 64 bytes (80 expected)");
  std::vector<uint8_t> head = parts.head;
  head[60] = 30;  // texture coordinate bits
  EXPECT_EQ(error_of([&] { MultilevelLoader("h", head, {}, compressed); }),
            "h: compressed head: 30 texture coordinate bits (1 to 24)");
  head = parts.head;
  const float inf = std::numeric_limits<float>::infinity();
  std::memcpy(head.data() + 72, &inf, 4);
  EXPECT_EQ(error_of([&] { MultilevelLoader("h", head, {}, compressed); }),
            "h: compressed head: the texture coordinates' box is not a box");
  MultilevelMesh plain = m;
  plain.texcoords.clear();
  head = multilevel_compressed_parts(plain).head;
  head[60] = 16;
  EXPECT_EQ(error_of([&] { MultilevelLoader("h", head, {}, compressed); }),
            "h: compressed head: texture coordinate bits without texture coordinates");
}

}  // namespace
}  // namespace pms
