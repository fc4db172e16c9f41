// save_ply: what it writes must load back bit for bit, in binary and ascii.
#include <cfloat>
#include <cmath>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>

#include "common/error.h"
#include "io/mesh.h"
#include "test_support.h"

namespace {

using pms::Mesh;

// Floats that a careless ascii writer would round: thirds, a subnormal, the extremes, -0.
Mesh awkward_mesh() {
  Mesh mesh;
  mesh.positions = {0.1f,  1.0f / 3.0f, -2.0f / 3.0f, FLT_MAX, -FLT_MIN, FLT_TRUE_MIN,
                    -0.0f, 1e-7f,       123456.789f,  1.0f,    -1.0f,    0.5f};
  mesh.normals = {0.0f, 0.0f, 1.0f, 0.577350269f, 0.577350269f, -0.577350269f, 1.0f, 0.0f, 0.0f, -0.6f, 0.8f, 0.0f};
  mesh.colors = {0, 1, 2, 3, 255, 128, 64, 32, 10, 20, 30, 40, 250, 251, 252, 253};
  mesh.texcoords = {0.0f, 1.0f, 1.0f / 3.0f, -0.0f, 2.5f, 1e-7f, -0.25f, 0.999999f};
  mesh.indices = {0, 1, 2, 0, 2, 3, 3, 2, 1};
  return mesh;
}

void expect_identical(const Mesh& a, const Mesh& b) {
  EXPECT_EQ(a.positions, b.positions);
  EXPECT_EQ(a.normals, b.normals);
  EXPECT_EQ(a.colors, b.colors);
  EXPECT_EQ(a.texcoords, b.texcoords);
  EXPECT_EQ(a.indices, b.indices);
  // == treats -0 and 0 alike; the bits must survive too.
  for (size_t i = 0; i < a.positions.size() && i < b.positions.size(); ++i)
    EXPECT_EQ(std::signbit(a.positions[i]), std::signbit(b.positions[i])) << "coordinate " << i;
}

std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

class SavePly : public testing::TestWithParam<bool> {};

TEST_P(SavePly, RoundTripKeepsEverythingExactly) {
  const Mesh mesh = awkward_mesh();
  const std::string path = (pms::test::temp_dir() / "awkward.ply").string();
  pms::save_ply(mesh, path, GetParam());
  expect_identical(pms::load_mesh(path), mesh);
}

TEST_P(SavePly, RoundTripWithoutNormalsOrColors) {
  Mesh mesh = awkward_mesh();
  mesh.normals.clear();
  mesh.colors.clear();
  mesh.texcoords.clear();
  const std::string path = (pms::test::temp_dir() / "plain.ply").string();
  pms::save_ply(mesh, path, GetParam());
  const Mesh loaded = pms::load_mesh(path);
  EXPECT_FALSE(loaded.has_normals());
  EXPECT_FALSE(loaded.has_colors());
  EXPECT_FALSE(loaded.has_texcoords());
  expect_identical(loaded, mesh);
}

TEST_P(SavePly, RoundTripOfARealScan) {
  PMS_REQUIRE_SHARED_MODEL(model, "horse.ply.xz");
  const Mesh mesh = pms::load_mesh(model.string());
  const std::string path = (pms::test::temp_dir() / "horse.ply").string();
  pms::save_ply(mesh, path, GetParam());
  expect_identical(pms::load_mesh(path), mesh);
}

INSTANTIATE_TEST_SUITE_P(Encodings, SavePly, testing::Bool(),
                         [](const testing::TestParamInfo<bool>& info) { return info.param ? "Binary" : "Ascii"; });

TEST(SavePlyFormat, HeaderDeclaresTheAttributesPresent) {
  const std::string path = (pms::test::temp_dir() / "header.ply").string();
  pms::save_ply(awkward_mesh(), path);
  const std::string text = read_text(path);
  const std::string header = text.substr(0, text.find("end_header\n") + 11);
  EXPECT_EQ(header.rfind("ply\nformat binary_little_endian 1.0\n", 0), 0u);
  for (const char* line : {"element vertex 4\n", "property float x\n", "property float nz\n", "property uchar red\n",
                           "property uchar alpha\n", "property float s\n", "property float t\n", "element face 3\n",
                           "property list uchar int vertex_indices\n"})
    EXPECT_NE(header.find(line), std::string::npos) << line;
  // 4 vertices of 3+3+2 floats and 4 bytes, 3 faces of a count byte and 3 ints.
  EXPECT_EQ(text.size() - header.size(), 4u * 36 + 3u * 13);
}

TEST(SavePlyFormat, AsciiIsOneRecordPerLine) {
  const std::string path = (pms::test::temp_dir() / "ascii.ply").string();
  Mesh mesh = awkward_mesh();
  mesh.normals.clear();
  mesh.texcoords.clear();
  pms::save_ply(mesh, path, false);
  const std::string text = read_text(path);
  const std::string body = text.substr(text.find("end_header\n") + 11);
  EXPECT_EQ(body,
            "0.1 0.33333334 -0.6666667 0 1 2 3\n"
            "3.4028235e+38 -1.1754944e-38 1e-45 255 128 64 32\n"
            "-0 1e-07 123456.79 10 20 30 40\n"
            "1 -1 0.5 250 251 252 253\n"
            "3 0 1 2\n3 0 2 3\n3 3 2 1\n");
}

TEST(SavePlyErrors, BadMeshOrPathNamesTheFile) {
  const std::string dir = pms::test::temp_dir().string();
  Mesh broken = awkward_mesh();
  broken.indices.back() = 4;
  try {
    pms::save_ply(broken, dir + "/broken.ply");
    FAIL() << "an out-of-range index must not be written";
  } catch (const pms::Error& e) {
    EXPECT_EQ(std::string(e.what()), dir + "/broken.ply: cannot save: face index 4 out of range");
  }
  try {
    pms::save_ply(awkward_mesh(), dir + "/no/such/dir/out.ply");
    FAIL() << "writing into a missing directory must fail";
  } catch (const pms::Error& e) {
    EXPECT_EQ(std::string(e.what()).rfind(dir + "/no/such/dir/out.ply: cannot create", 0), 0u) << e.what();
  }
}

}  // namespace
