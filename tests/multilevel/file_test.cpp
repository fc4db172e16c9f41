// Multilevel files: the paper's own examples (gueziec et al. 1999, Fig. 6 and Fig. 13), exact round trips
// of both forms, and clear errors for malformed input.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>

#include "common/error.h"
#include "error_of.h"
#include "expect.h"
#include "fixtures/view_models.h"
#include "multilevel/build.h"
#include "multilevel/file.h"
#include "test_support.h"

namespace pms {
namespace {

// Fig. 6 as printed, with its one typo ("3.0. -3.0" for "3.0, -3.0") corrected.
constexpr const char* kFigure6 = R"(#3-level progressive mesh
{#level 2 vertices      (4)
-3.0, 3.0, 3.0, 3.0, -3.0, -3.0
3.0, -3.0}
{#level 2 triangles (2), followed with
#                      representatives
6, 2, 8, 0, 1,
3, 8, 2}
{#level 1 vertices      (3)
-2.3, 3.0, -3.0, 2.3, 2.3, 2.3}
{#level 1 triangles      (4)
4, 6, 7, 1,
5, 2, 6,
6, 4, 5,
4, 0, 5}
{#level 0 vertices      (3)
2.3, 3.0, 2.3, 2.3, 3.0, 2.3}
{#level 0 triangles (no representatives
#necessary)
8, 3, 9,
9, 1, 8,
7, 8, 1,
8, 7, 6}
)";

constexpr const char* kFigure13 = R"(#2-level progressive mesh
{#level 2 vertices
0, 0, 0, 2, 2, 0, 2, 0, 2,
0, 2, 2}
{#level 2 triangles
0, 4, 5, 1, 2,
5, 4, 6, 3,
6, 0, 5,
4, 0, 6}
{#level 1 vertices
1, 1, 0, 1, 0, 1, 0, 1, 1,
2, 1, 1, 1, 2, 1, 1, 1, 2}
{#level 1 triangles
8, 6, 3,
3, 6, 9,
9, 8, 3,
6, 8, 9,
7, 5, 9,
9, 5, 2,
2, 7, 9,
5, 7, 2,
1, 4, 8,
8, 4, 7,
7, 1, 8,
4, 1, 7}
)";

const auto expect_same = test::expect_same_multilevel;

using test::error_of;

std::string ascii_error(const std::string& text) {
  return error_of([&] { parse_multilevel_ascii("m.txt", text); });
}

TEST(MultilevelFile, Figure6ParsesWithItsLevelsAndThreeRepresentatives) {
  const MultilevelMesh m = parse_multilevel_ascii("fig6", kFigure6);
  EXPECT_EQ(m.dimension, 2u);
  EXPECT_EQ(m.vertex_count, (std::vector<uint32_t>{10, 7, 4}));
  EXPECT_EQ(m.triangle_count, (std::vector<uint32_t>{10, 6, 2}));
  EXPECT_EQ(m.stored_representatives(), 3u);
  EXPECT_EQ(m.representative[6], 0u);
  EXPECT_EQ(m.representative[8], 1u);
  EXPECT_EQ(m.representative[7], 1u);
  MultilevelLod lod(m);
  lod.set_level(2u);  // "Vertex 6 requires a representative (this is 0) as well as vertex 8 (1)"
  EXPECT_EQ(std::vector<uint32_t>(lod.indices().begin(), lod.indices().end()),
            (std::vector<uint32_t>{0, 2, 1, 3, 1, 2}));
  lod.set_level(1u);
  // (6, 2, 8): 6 is in level 1, 8 is not; (4, 6, 7): 7 is missing from level 1, its representative is 1.
  EXPECT_EQ(std::vector<uint32_t>(lod.indices().begin(), lod.indices().begin() + 9),
            (std::vector<uint32_t>{6, 2, 1, 3, 1, 2, 4, 6, 1}));
  // Written back, it reads the same, in both forms.
  expect_same(parse_multilevel_ascii("again", format_multilevel_ascii(m)), m);
  expect_same(parse_multilevel_binary("again", format_multilevel_binary(m)), m);
}

TEST(MultilevelFile, An2DMeshThatWouldReadAs3DIsNotWritten) {
  MultilevelMesh m;
  m.dimension = 2;
  m.positions = {0, 0, 1, 0, 0, 1};
  m.triangles = {0, 1, 2};
  m.representative.assign(3, MultilevelMesh::kNoRepresentative);
  m.vertex_count = {3};
  m.triangle_count = {1};
  EXPECT_EQ(error_of([&] { format_multilevel_ascii(m); }),
            "a 2D mesh whose every level has a multiple of 3 vertices would read back as 3D from the ASCII form");
  expect_same(parse_multilevel_binary("2d", format_multilevel_binary(m)), m);  // the binary form says its dimension
}

TEST(MultilevelFile, Figure6AsPrintedIsRefusedAtItsTypo) {
  std::string printed = kFigure6;
  printed.replace(printed.find("3.0, -3.0}"), 4, "3.0.");
  EXPECT_EQ(ascii_error(printed), "m.txt: line 4: '3.0.' is not a finite number");
}

TEST(MultilevelFile, Figure13GivesFigure11sTriangleCountsWithThreeRepresentatives) {
  const MultilevelMesh m = parse_multilevel_ascii("fig13", kFigure13);
  EXPECT_EQ(m.dimension, 3u);
  ASSERT_EQ(m.level_count(), 2u);
  EXPECT_EQ(m.vertex_count, (std::vector<uint32_t>{10, 4}));
  EXPECT_EQ(m.triangle_count, (std::vector<uint32_t>{16, 4})) << "Fig. 11: levels of 16 and 4 triangles";
  EXPECT_EQ(m.stored_representatives(), 3u) << "\"Note that three representatives suffice\"";
  EXPECT_EQ(m.representative[4], 1u);
  EXPECT_EQ(m.representative[5], 2u);
  EXPECT_EQ(m.representative[6], 3u);
  MultilevelLod lod(m);
  lod.set_level(1u);  // the tetrahedron
  EXPECT_EQ(std::vector<uint32_t>(lod.indices().begin(), lod.indices().end()),
            (std::vector<uint32_t>{0, 1, 2, 2, 1, 3, 3, 0, 2, 1, 0, 3}));
  expect_same(parse_multilevel_ascii("again", format_multilevel_ascii(m)), m);
  expect_same(parse_multilevel_binary("again", format_multilevel_binary(m)), m);
}

MultilevelMesh built_terrain_multilevel(bool attributes,
                                        MultilevelRepresentatives kind = MultilevelRepresentatives::geomorph) {
  const test::BuiltModel& model = test::built_terrain();
  Mesh input = model.input;
  if (attributes) {
    input.normals.assign(input.vertex_count() * 3, 0);
    input.colors.assign(input.vertex_count() * 4, 0);
    for (size_t v = 0; v < input.vertex_count(); ++v) {
      input.normals[3 * v + 2] = 1;
      input.colors[4 * v] = uint8_t(v), input.colors[4 * v + 1] = uint8_t(v >> 8);
    }
  }
  return build_multilevel(input, collapses_of(model.h), 0, kind);
}

TEST(MultilevelFile, BuiltMeshRoundTripsExactlyInBothForms) {
  // The ASCII form holds the discrete LODs' representatives (the paper's form has no place for a
  // geomorph's): a geomorph build reads back as the discrete build.
  const MultilevelMesh plain = built_terrain_multilevel(false, MultilevelRepresentatives::discrete);
  const std::string text = format_multilevel_ascii(plain);
  expect_same(parse_multilevel_ascii("terrain.txt", text), plain);
  expect_same(parse_multilevel_ascii("terrain.txt", format_multilevel_ascii(built_terrain_multilevel(false))), plain);
  const MultilevelMesh rich = built_terrain_multilevel(true);
  const std::vector<uint8_t> bytes = format_multilevel_binary(rich);
  expect_same(parse_multilevel_binary("terrain.pml", bytes), rich);
  EXPECT_LT(bytes.size(), text.size());

  const auto dir = test::temp_dir();
  write_multilevel((dir / "a.txt").string(), plain, true);
  write_multilevel((dir / "a.pml").string(), rich, false);
  expect_same(read_multilevel((dir / "a.txt").string()), plain);
  expect_same(read_multilevel((dir / "a.pml").string()), rich);
  EXPECT_FALSE(std::filesystem::exists(dir / "a.pml.tmp"));
}

TEST(MultilevelFile, BunnyRoundTripsExactly) {
  const test::BuiltModel* bunny = test::built_bunny();
  if (!bunny) GTEST_SKIP() << "../shared/models/bunny.ply.xz not found: this test needs the shared test meshes";
  const MultilevelMesh m = build_multilevel(bunny->input, collapses_of(bunny->h), 8);
  ASSERT_GT(geomorph_representative_count(m), 0u) << "merged levels need representatives for geomorphs";
  expect_same(parse_multilevel_binary("bunny.pml", format_multilevel_binary(m)), m);
  const MultilevelMesh discrete =
      build_multilevel(bunny->input, collapses_of(bunny->h), 8, MultilevelRepresentatives::discrete);
  const std::string text = format_multilevel_ascii(m);
  EXPECT_NE(text.find("#(without the " + std::to_string(geomorph_representative_count(m)) +
                      " representatives only geomorphs use)\n"),
            std::string::npos);
  expect_same(parse_multilevel_ascii("bunny.txt", text), discrete);
}

TEST(MultilevelFile, MalformedAsciiNamesTheLine) {
  const std::pair<const char*, const char*> cases[] = {
      {"", "m.txt: no levels: the file holds no { } batch"},
      {"# only a comment\n", "m.txt: no levels: the file holds no { } batch"},
      {"{0,0,0}\n{", "m.txt: line 2: '{' is never closed"},
      {"{0,0,0}\n}", "m.txt: line 2: '}' without '{'"},
      {"7\n{0,0,0}{}", "m.txt: line 1: a number outside { }"},
      {"{0,0,0 {1}}", "m.txt: line 1: '{' inside a batch (the batch opened on line 1)"},
      {"{0,0,0}", "m.txt: the last level has vertices but no triangle batch (an empty one is {})"},
      {"{0,0,0,1,1,1,1}{}", "m.txt: line 1: a vertex batch of 7 numbers is not whole 2D or 3D vertices"},
      {"{0,0,0, 1,0,0, 0,1,0}\n{0, 1}", "m.txt: line 2: a triangle of level 0 has 2 corners, not 3"},
      {"{0,0,0, 1,0,0}\n{0, 1, 2}{0,1,0}{}",
       "m.txt: line 2: vertex 2 is not in level 1 or above: its representative must follow the triangle"},
      {"{0,0,0, 1,0,0}\n{0, 1, 2, 2}{0,1,0}{}", "m.txt: line 2: representative 2 of vertex 2 is not below it"},
      {"{0,0,0, 1,0,0, 0,1,0}\n{0, 1, 5}", "m.txt: line 2: vertex 5 is beyond the file's 3 vertices"},
      {"{0,0,0, 1,0,0, 0,1,0}\n{0, 1, x}", "m.txt: line 2: 'x' is not a vertex index"},
      {"{0,0,0, 1,0,0, 0,1,0}\n{0, 1, -2}", "m.txt: line 2: '-2' is not a vertex index"},
      {"{0,0,0, 1,0,0, 0,1,nan}\n{}", "m.txt: line 1: 'nan' is not a finite number"},
      {"{0,0,0, 1,0,0}\n{0, 1,\n 2, 7}{0,1,0}{}", "m.txt: line 3: representative 7 is beyond the file's 3 vertices"},
      {"{0,0,0, 1,0,0, 0,1,0}{0,1,99999999999}", "m.txt: line 1: '99999999999' is not a vertex index"},
  };
  for (const auto& [text, expected] : cases) EXPECT_EQ(ascii_error(text), expected) << "input: " << text;
}

std::string binary_error(const std::vector<uint8_t>& bytes) {
  return error_of([&] { parse_multilevel_binary("m.pml", bytes); });
}

TEST(MultilevelFile, MalformedBinaryNamesTheOffset) {
  const std::vector<uint8_t> good = format_multilevel_binary(parse_multilevel_ascii("fig13", kFigure13));
  auto bad = good;
  bad.resize(good.size() - 4);
  EXPECT_EQ(binary_error(bad), "m.pml: offset 24: header: file size " + std::to_string(good.size()) + " but " +
                                   std::to_string(bad.size()) + " bytes read (truncated?)");
  bad = good;
  bad[0] = 'X';
  EXPECT_EQ(binary_error(bad), "m.pml: offset 0: header: not a binary multilevel file (magic)");
  bad = good;
  bad[8] = 9;
  EXPECT_EQ(binary_error(bad), "m.pml: offset 8: header: unsupported version 9 (this build reads 1)");
  bad = good;
  bad.back() ^= 1;
  EXPECT_NE(binary_error(bad).find("(LEVL): checksum mismatch"), std::string::npos) << binary_error(bad);
  bad = good;
  bad[20] = 1;
  EXPECT_EQ(binary_error(bad), "m.pml: offset 20: header: unknown flags 1");
  EXPECT_EQ(binary_error({}), "m.pml: offset 0: header: 0 bytes, too short for a header");

  // Past the checksums: a representative that is not below its vertex, and a level's counts that lie.
  uint64_t last_offset = 0;
  std::memcpy(&last_offset, good.data() + 40 + 32 * 2 + 8, 8);  // the finest level's LEVL
  uint64_t first_level = 0;
  std::memcpy(&first_level, good.data() + 40 + 32 + 8, 8);  // the coarsest level's LEVL
  bad = good;
  const uint32_t self = 4;  // triangle (0, 4, 5) states 4 -> 1: make it 4 -> 4
  std::memcpy(bad.data() + first_level + 4 * (4 + 12 + 12 + 1), &self, 4);
  reseal_multilevel_binary(bad);
  EXPECT_EQ(binary_error(bad), "m.pml: vertex 4 has representative 4, which is not below it");
  bad = good;
  const uint32_t many = 1000;
  std::memcpy(bad.data() + last_offset + 4, &many, 4);
  reseal_multilevel_binary(bad);
  EXPECT_NE(binary_error(bad).find("section LEVL of level 0: 58 words but its counts need"), std::string::npos)
      << binary_error(bad);
}

}  // namespace
}  // namespace pms
