// load_mesh: every format on small hand-written files, the shared real scans, compression, and
// the error cases (each error must be one line that starts with the file's name).
#include <lzma.h>
#include <zlib.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cstring>
#include <fstream>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "common/error.h"
#include "io/decompress.h"
#include "io/mesh.h"
#include "test_support.h"

namespace {

using pms::Mesh;

std::string write_file(const std::string& name, std::string_view bytes) {
  const auto path = (pms::test::temp_dir() / name).string();
  std::ofstream(path, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
  return path;
}

std::vector<uint8_t> to_bytes(std::string_view s) { return {s.begin(), s.end()}; }

template <class Fn>
std::string error_of(Fn&& fn) {
  try {
    fn();
  } catch (const pms::Error& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected a pms::Error";
  return {};
}

// The message names the file first, states `problem`, and is a single line.
void expect_load_error(const std::string& path, const std::string& problem) {
  const std::string message = error_of([&] { pms::load_mesh(path); });
  EXPECT_EQ(message.rfind(path + ": ", 0), 0u) << message;
  EXPECT_NE(message.find(problem), std::string::npos) << message;
  EXPECT_EQ(message.find('\n'), std::string::npos) << message;
}

// Binary records in either byte order.
class Bytes {
 public:
  explicit Bytes(bool big_endian) : big_endian_(big_endian) {}
  template <class T>
  Bytes& put(T value) {
    char raw[sizeof(T)];
    std::memcpy(raw, &value, sizeof(T));
    if (big_endian_ != (std::endian::native == std::endian::big)) std::reverse(raw, raw + sizeof(T));
    data.append(raw, sizeof(T));
    return *this;
  }
  std::string data;

 private:
  bool big_endian_;
};

// ---- PLY -------------------------------------------------------------------------------------

const char* kPentagonPly =
    "ply\n"
    "format ascii 1.0\n"
    "comment a convex pentagon as one polygon\n"
    "element vertex 5\n"
    "property float x\nproperty float y\nproperty float z\n"
    "element face 1\n"
    "property list uchar int vertex_indices\n"
    "end_header\n"
    "0 0 0\n1 0 0\n2 1 0\n1 2 0\n0 1 0\n"
    "5 0 1 2 3 4\n";

TEST(ImportPly, AsciiPolygonIsFanTriangulated) {
  const Mesh mesh = pms::load_mesh(write_file("pentagon.ply", kPentagonPly));
  EXPECT_EQ(mesh.vertex_count(), 5u);
  EXPECT_EQ(mesh.indices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3, 0, 3, 4}));
  EXPECT_EQ(mesh.positions[6], 2.0f);
  EXPECT_EQ(mesh.positions[7], 1.0f);
  EXPECT_FALSE(mesh.has_normals());
  EXPECT_FALSE(mesh.has_colors());
}

TEST(ImportPly, AsciiWithCrLfLineEnds) {
  std::string crlf;
  for (const char* c = kPentagonPly; *c; ++c) crlf += *c == '\n' ? std::string("\r\n") : std::string(1, *c);
  const Mesh mesh = pms::load_mesh(write_file("crlf.ply", crlf));
  EXPECT_EQ(mesh.indices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3, 0, 3, 4}));
}

// Every scalar type and alias, skipped properties and lists, an extra element, and a face list
// named vertex_index with ushort counts and uint indices.
std::string all_types_ply(bool big_endian) {
  std::string ply = std::string("ply\nformat ") + (big_endian ? "binary_big_endian" : "binary_little_endian") +
                    " 1.0\n"
                    "element vertex 4\n"
                    "property char a\nproperty uchar b\nproperty short c\nproperty ushort d\n"
                    "property int e\nproperty uint f\nproperty float x\nproperty double y\n"
                    "property int8 g\nproperty uint8 h\nproperty int16 i\nproperty uint16 j\n"
                    "property int32 k\nproperty uint32 l\nproperty float32 z\nproperty float64 m\n"
                    "property list uchar float extra\n"
                    "property float nx\nproperty float ny\nproperty float nz\n"
                    "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n"
                    "element edge 2\n"
                    "property int vertex1\nproperty list int int path\n"
                    "element face 2\n"
                    "property uchar flags\n"
                    "property list ushort uint vertex_index\n"
                    "end_header\n";
  Bytes body(big_endian);
  for (int v = 0; v < 4; ++v) {
    body.put<int8_t>(-1).put<uint8_t>(2).put<int16_t>(-3).put<uint16_t>(4).put<int32_t>(-5).put<uint32_t>(6);
    body.put<float>(float(v) + 0.5f).put<double>(0.25 * v);
    body.put<int8_t>(-7).put<uint8_t>(8).put<int16_t>(-9).put<uint16_t>(10).put<int32_t>(-11).put<uint32_t>(12);
    body.put<float>(-float(v)).put<double>(13.0);
    body.put<uint8_t>(uint8_t(v));
    for (int k = 0; k < v; ++k) body.put<float>(99.0f);
    body.put<float>(0.0f).put<float>(0.6f).put<float>(0.8f);
    body.put<uint8_t>(uint8_t(10 * v)).put<uint8_t>(20).put<uint8_t>(30).put<uint8_t>(40);
  }
  body.put<int32_t>(0).put<int32_t>(2).put<int32_t>(0).put<int32_t>(1);
  body.put<int32_t>(1).put<int32_t>(0);
  body.put<uint8_t>(7).put<uint16_t>(4).put<uint32_t>(0).put<uint32_t>(1).put<uint32_t>(2).put<uint32_t>(3);
  body.put<uint8_t>(7).put<uint16_t>(3).put<uint32_t>(3).put<uint32_t>(2).put<uint32_t>(1);
  return ply + body.data;
}

void expect_all_types_mesh(const Mesh& mesh) {
  ASSERT_EQ(mesh.vertex_count(), 4u);
  for (int v = 0; v < 4; ++v) {
    EXPECT_EQ(mesh.positions[v * 3 + 0], float(v) + 0.5f);
    EXPECT_EQ(mesh.positions[v * 3 + 1], 0.25f * float(v));
    EXPECT_EQ(mesh.positions[v * 3 + 2], -float(v));
  }
  ASSERT_TRUE(mesh.has_normals());
  EXPECT_EQ(mesh.normals[3 * 3 + 1], 0.6f);
  EXPECT_EQ(mesh.normals[3 * 3 + 2], 0.8f);
  ASSERT_TRUE(mesh.has_colors());
  EXPECT_EQ(std::vector<uint8_t>(mesh.colors.begin() + 12, mesh.colors.end()), (std::vector<uint8_t>{30, 20, 30, 40}));
  EXPECT_EQ(mesh.indices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3, 3, 2, 1}));
}

TEST(ImportPly, BinaryLittleEndianAllScalarTypes) {
  expect_all_types_mesh(pms::load_mesh(write_file("types_le.ply", all_types_ply(false))));
}

TEST(ImportPly, BinaryBigEndianAllScalarTypes) {
  expect_all_types_mesh(pms::load_mesh(write_file("types_be.ply", all_types_ply(true))));
}

TEST(ImportPly, UcharColorsWithoutAlphaAreOpaque) {
  const Mesh mesh = pms::load_mesh(write_file("colors.ply",
                                              "ply\nformat ascii 1.0\nelement vertex 3\n"
                                              "property float x\nproperty float y\nproperty float z\n"
                                              "property uchar red\nproperty uchar green\nproperty uchar blue\n"
                                              "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
                                              "0 0 0 255 0 0\n1 0 0 0 255 0\n0 1 0 1 2 3\n3 0 1 2\n"));
  EXPECT_EQ(mesh.colors, (std::vector<uint8_t>{255, 0, 0, 255, 0, 255, 0, 255, 1, 2, 3, 255}));
}

TEST(ImportPly, FloatColorsAreScaledTo8Bits) {
  const Mesh mesh = pms::load_mesh(write_file("float_colors.ply",
                                              "ply\nformat ascii 1.0\nelement vertex 3\n"
                                              "property float x\nproperty float y\nproperty float z\n"
                                              "property float red\nproperty float green\nproperty float blue\n"
                                              "property float alpha\n"
                                              "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
                                              "0 0 0 1 0.5 0 1\n1 0 0 0 0 0 0\n0 1 0 2 -1 0.25 0.5\n3 0 1 2\n"));
  EXPECT_EQ(mesh.colors, (std::vector<uint8_t>{255, 128, 0, 255, 0, 0, 0, 0, 255, 0, 64, 128}));
}

// Each spelling of texture coordinates, as float and as double, ascii and binary; a property other than
// s/t between them is skipped, and only one of u and v is not enough.
TEST(ImportPly, TextureCoordinatesUnderEveryName) {
  for (const auto& [u, v] : {std::pair{"s", "t"}, {"u", "v"}, {"texture_u", "texture_v"}, {"texture_s", "texture_t"}}) {
    const std::string head = std::string("ply\nformat ascii 1.0\nelement vertex 3\n") +
                             "property float x\nproperty float y\nproperty float z\nproperty float " + u +
                             "\nproperty uchar quality\nproperty double " + v +
                             "\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
    const Mesh mesh = pms::load_mesh(write_file(
        std::string("uv_") + u + ".ply", head + "0 0 0 0.25 7 0.75\n1 0 0 1 7 -0.5\n0 1 0 2.5 7 0.1\n3 0 1 2\n"));
    ASSERT_TRUE(mesh.has_texcoords()) << u;
    EXPECT_EQ(mesh.texcoords, (std::vector<float>{0.25f, 0.75f, 1.0f, -0.5f, 2.5f, 0.1f})) << u;
  }
  Bytes binary(true);
  for (int k = 0; k < 3; ++k)
    binary.put<float>(float(k)).put<float>(0).put<float>(0).put<double>(0.125 * k).put<double>(1 - 0.125 * k);
  binary.put<uint8_t>(3).put<int32_t>(0).put<int32_t>(1).put<int32_t>(2);
  const Mesh big = pms::load_mesh(write_file("uv_be.ply",
                                             "ply\nformat binary_big_endian 1.0\nelement vertex 3\n"
                                             "property float x\nproperty float y\nproperty float z\n"
                                             "property double texture_u\nproperty double texture_v\n"
                                             "element face 1\nproperty list uchar int vertex_indices\n"
                                             "end_header\n" +
                                                 binary.data));
  EXPECT_EQ(big.texcoords, (std::vector<float>{0, 1, 0.125f, 0.875f, 0.25f, 0.75f}));
  const Mesh half = pms::load_mesh(write_file("uv_half.ply",
                                              "ply\nformat ascii 1.0\nelement vertex 3\n"
                                              "property float x\nproperty float y\nproperty float z\n"
                                              "property float u\nelement face 1\n"
                                              "property list uchar int vertex_indices\nend_header\n"
                                              "0 0 0 1\n1 0 0 1\n0 1 0 1\n3 0 1 2\n"));
  EXPECT_FALSE(half.has_texcoords());
}

TEST(ImportPly, NonFiniteTextureCoordinatesFail) {
  expect_load_error(write_file("uv_nan.ply",
                               "ply\nformat ascii 1.0\nelement vertex 3\n"
                               "property float x\nproperty float y\nproperty float z\n"
                               "property float s\nproperty float t\nelement face 1\n"
                               "property list uchar int vertex_indices\nend_header\n"
                               "0 0 0 0 0\n1 0 0 0 0\n0 1 0 nan 0\n3 0 1 2\n"),
                    "vertex 2 has a NaN or infinite texture coordinate");
}

// ---- OBJ and OFF -----------------------------------------------------------------------------

TEST(ImportObj, ColorsCornerSyntaxNegativeIndicesAndPolygons) {
  const Mesh mesh = pms::load_mesh(write_file("square.obj",
                                              "# a square and a repeated half\n"
                                              "mtllib none.mtl\no square\n"
                                              "v 0 0 0 1 0 0\nv 1 0 0 0 1 0\n"
                                              "v 1 1 0 0 0 1\nv 0 1 0 1 1 1\n"
                                              "vn 0 0 1\nvt 0 0\ns off\n"
                                              "f 1/1/1 2/1/1 3/1/1 4/1/1\n"
                                              "f -4//1 -2//1 -1//1\n"));
  EXPECT_EQ(mesh.vertex_count(), 4u);
  EXPECT_EQ(mesh.indices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3, 0, 2, 3}));
  EXPECT_EQ(mesh.colors, (std::vector<uint8_t>{255, 0, 0, 255, 0, 255, 0, 255, 0, 0, 255, 255, 255, 255, 255, 255}));
  EXPECT_FALSE(mesh.has_normals());
  EXPECT_FALSE(mesh.has_texcoords()) << "the second face names no texture vertex";
}

// A texture seam: vertex 2 is used with texture vertices 2 and 4, so it is split in two; the copy comes
// after the input's vertices with the same position and colour. Corners may name the texture vertex
// counting back (-1) and carry a normal (a/t/n).
const char* kSeamObj =
    "v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nv 1 1 0 1 1 1\n"
    "vt 0 0\nvt 1 0\nvt 0 1\nvt 0.5 0.5\nvn 0 0 1\n"
    "f 1/1/1 2/2/1 3/3/1\n"
    "vt 0.9 0.9 0\n"
    "f 2/4/1 4/-1/1 3/3/1\n"
    "f 2/2 4/5 3/3\n";

TEST(ImportObj, TextureSeamSplitsTheVertex) {
  const Mesh mesh = pms::load_mesh(write_file("seam.obj", kSeamObj));
  ASSERT_EQ(mesh.vertex_count(), 5u);
  EXPECT_EQ(mesh.indices, (std::vector<uint32_t>{0, 1, 2, 4, 3, 2, 1, 3, 2}));
  EXPECT_EQ(mesh.texcoords, (std::vector<float>{0, 0, 1, 0, 0, 1, 0.9f, 0.9f, 0.5f, 0.5f}));
  EXPECT_EQ(std::vector<float>(mesh.positions.begin() + 12, mesh.positions.end()), (std::vector<float>{1, 0, 0}));
  EXPECT_EQ(std::vector<uint8_t>(mesh.colors.begin() + 16, mesh.colors.end()), (std::vector<uint8_t>{0, 255, 0, 255}));
}

TEST(ImportObj, TextureVertexIndexOutOfRangeNamesTheLine) {
  expect_load_error(write_file("bad_vt.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/2 3/1\n"),
                    "line 5: texture vertex index 2 out of range");
  expect_load_error(write_file("bad_vt_token.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 x\nf 1 2 3\n"),
                    "line 4: expected a texture coordinate");
  // A position index out of range is still load_mesh's to report, texture vertices or not.
  expect_load_error(write_file("bad_v_textured.obj", "v 0 0 0\nv 1 0 0\nvt 0 0\nf 1/1 2/1 3/1\n"),
                    "face 0 uses vertex 2 but there are only 2 vertices");
}

TEST(ImportObj, ColorsAreDroppedUnlessEveryVertexHasOne) {
  const Mesh mesh = pms::load_mesh(write_file("mixed.obj", "v 0 0 0 1 0 0\nv 1 0 0\nv 0 1 0 0 0 1\nf 1 2 3\n"));
  EXPECT_EQ(mesh.face_count(), 1u);
  EXPECT_FALSE(mesh.has_colors());
}

TEST(ImportOff, PolygonsCommentsAndFaceColors) {
  const Mesh mesh = pms::load_mesh(write_file("pyramid.off",
                                              "OFF\n# a square pyramid\n5 5 8\n"
                                              "0 0 0\n1 0 0\n1 1 0\n0 1 0\n0.5 0.5 1  # apex\n"
                                              "4 3 2 1 0\n3 0 1 4\n3 1 2 4  255 0 0\n\n3 2 3 4\n3 3 0 4\n"));
  EXPECT_EQ(mesh.vertex_count(), 5u);
  EXPECT_EQ(mesh.face_count(), 6u);
  EXPECT_EQ(std::vector<uint32_t>(mesh.indices.begin(), mesh.indices.begin() + 6),
            (std::vector<uint32_t>{3, 2, 1, 3, 1, 0}));
  EXPECT_EQ(mesh.positions[14], 1.0f);
}

TEST(ImportOff, IntegerAndUnitRangeVertexColors) {
  const Mesh ints = pms::load_mesh(write_file("ints.off",
                                              "COFF\n3 1 0\n0 0 0 255 0 0 255\n1 0 0 0 255 0 128\n"
                                              "0 1 0 0 0 255 255\n3 0 1 2\n"));
  EXPECT_EQ(ints.colors, (std::vector<uint8_t>{255, 0, 0, 255, 0, 255, 0, 128, 0, 0, 255, 255}));
  const Mesh units = pms::load_mesh(write_file("units.off",
                                               "COFF 3 1 0\n0 0 0 1.0 0.5 0.0\n1 0 0 0 0 0 0.0\n"
                                               "0 1 0 0.0 0.0 1.0 1.0\n3 0 1 2\n"));
  EXPECT_EQ(units.colors, (std::vector<uint8_t>{255, 128, 0, 255, 0, 0, 0, 0, 0, 0, 255, 255}));
}

// ---- assimp formats --------------------------------------------------------------------------

using Point = std::array<float, 3>;
using Triangle = std::array<Point, 3>;

// A triangle as its corner positions, rotated to start at the smallest, so orientation counts.
Triangle canonical(Triangle t) {
  std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
  return t;
}

std::multiset<Triangle> triangles_of(const Mesh& mesh) {
  std::multiset<Triangle> out;
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    Triangle t;
    for (int c = 0; c < 3; ++c)
      for (int k = 0; k < 3; ++k) t[c][k] = mesh.positions[mesh.indices[f * 3 + c] * 3 + k];
    out.insert(canonical(t));
  }
  return out;
}

// A tetrahedron, faces counter-clockwise seen from outside.
const std::array<Triangle, 4> kTetrahedron = {{
    {{{0, 0, 0}, {0, 1, 0}, {1, 0, 0}}},
    {{{0, 0, 0}, {1, 0, 0}, {0, 0, 1}}},
    {{{0, 0, 0}, {0, 0, 1}, {0, 1, 0}}},
    {{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}},
}};

void expect_welded_tetrahedron(const Mesh& mesh) {
  EXPECT_EQ(mesh.vertex_count(), 4u) << "STL corners must be welded into shared vertices";
  std::multiset<Triangle> expected;
  for (const Triangle& t : kTetrahedron) expected.insert(canonical(t));
  EXPECT_EQ(triangles_of(mesh), expected);
}

TEST(ImportAssimp, AsciiStl) {
  std::string stl = "solid tet\n";
  for (const Triangle& t : kTetrahedron) {
    stl += "facet normal 0 0 0\n outer loop\n";
    for (const Point& p : t)
      stl += "  vertex " + std::to_string(p[0]) + " " + std::to_string(p[1]) + " " + std::to_string(p[2]) + "\n";
    stl += " endloop\nendfacet\n";
  }
  stl += "endsolid tet\n";
  expect_welded_tetrahedron(pms::load_mesh(write_file("tet_ascii.stl", stl)));
}

TEST(ImportAssimp, BinaryStl) {
  Bytes stl(false);
  stl.data = std::string(80, ' ');  // a binary header must not start with "solid"
  stl.put<uint32_t>(uint32_t(kTetrahedron.size()));
  for (const Triangle& t : kTetrahedron) {
    for (int k = 0; k < 3; ++k) stl.put<float>(0.0f);
    for (const Point& p : t)
      for (float x : p) stl.put<float>(x);
    stl.put<uint16_t>(0);
  }
  expect_welded_tetrahedron(pms::load_mesh(write_file("tet_binary.stl", stl.data)));
}

// One triangle instanced by two nodes (the second moved by +10 in x) and a point primitive that
// must be dropped; the buffer is an embedded data URI (3 float positions, 3 uint16 indices).
const char* kGltf = R"({
  "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0, 1, 2]}],
  "nodes": [{"mesh": 0}, {"mesh": 0, "translation": [10, 0, 0]}, {"mesh": 1}],
  "meshes": [{"primitives": [{"attributes": {"POSITION": 1}, "indices": 0}]},
             {"primitives": [{"attributes": {"POSITION": 1}, "mode": 0}]}],
  "buffers": [{"byteLength": 44, "uri": "data:application/octet-stream;base64,)"
                    "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAABAAIAAAA="
                    R"("}],
  "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36, "target": 34962},
                  {"buffer": 0, "byteOffset": 36, "byteLength": 6, "target": 34963}],
  "accessors": [{"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR", "min": [0], "max": [2]},
                {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                 "min": [0, 0, 0], "max": [1, 1, 0]}]
})";

// One triangle with TEXCOORD_0 (glTF's v runs down the image; assimp hands it over with v up, 1 - v).
const char* kTexturedGltf =
    R"({
  "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
  "meshes": [{"primitives": [{"attributes": {"POSITION": 1, "TEXCOORD_0": 2}, "indices": 0}]}],
  "buffers": [{"byteLength": 68, "uri": "data:application/octet-stream;base64,)"
    "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAACAPgAAQD8AAIA/AAAAPwAAAAAAAAAAAAABAAIAAAA="
    R"("}],
  "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36, "target": 34962},
                  {"buffer": 0, "byteOffset": 36, "byteLength": 24, "target": 34962},
                  {"buffer": 0, "byteOffset": 60, "byteLength": 6, "target": 34963}],
  "accessors": [{"bufferView": 2, "componentType": 5123, "count": 3, "type": "SCALAR", "min": [0], "max": [2]},
                {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                 "min": [0, 0, 0], "max": [1, 1, 0]},
                {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2"}]
})";

TEST(ImportAssimp, GltfTexcoord0BecomesTheTextureCoordinates) {
  const Mesh mesh = pms::load_mesh(write_file("textured.gltf", kTexturedGltf));
  ASSERT_EQ(mesh.vertex_count(), 3u);
  ASSERT_TRUE(mesh.has_texcoords());
  // The file's (0.25, 0.75), (1, 0.5), (0, 0), in the order assimp gives the vertices.
  std::multiset<std::pair<float, float>> uv;
  for (size_t v = 0; v < 3; ++v) uv.insert({mesh.texcoords[2 * v], mesh.texcoords[2 * v + 1]});
  EXPECT_EQ(uv, (std::multiset<std::pair<float, float>>{{0.25f, 0.25f}, {1.0f, 0.5f}, {0.0f, 1.0f}}));
  EXPECT_FALSE(pms::load_mesh(write_file("untextured.gltf", kGltf)).has_texcoords());
}

TEST(ImportAssimp, GltfMergesInstancesWithNodeTransforms) {
  const Mesh mesh = pms::load_mesh(write_file("instances.gltf", kGltf));
  EXPECT_EQ(mesh.vertex_count(), 6u) << "the point primitive adds no vertices";
  const std::multiset<Triangle> expected = {canonical({{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}}),
                                            canonical({{{10, 0, 0}, {11, 0, 0}, {10, 1, 0}}})};
  EXPECT_EQ(triangles_of(mesh), expected);
}

// ---- compression -----------------------------------------------------------------------------

std::string gzip(std::string_view text) {
  z_stream zs{};
  EXPECT_EQ(deflateInit2(&zs, 9, Z_DEFLATED, 16 + MAX_WBITS, 8, Z_DEFAULT_STRATEGY), Z_OK);
  std::string out(deflateBound(&zs, uLong(text.size())), '\0');
  zs.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(text.data()));
  zs.avail_in = uInt(text.size());
  zs.next_out = reinterpret_cast<Bytef*>(out.data());
  zs.avail_out = uInt(out.size());
  EXPECT_EQ(deflate(&zs, Z_FINISH), Z_STREAM_END);
  out.resize(zs.total_out);
  deflateEnd(&zs);
  return out;
}

std::string xz(std::string_view text) {
  std::string out(lzma_stream_buffer_bound(text.size()), '\0');
  size_t used = 0;
  EXPECT_EQ(lzma_easy_buffer_encode(6, LZMA_CHECK_CRC64, nullptr, reinterpret_cast<const uint8_t*>(text.data()),
                                    text.size(), reinterpret_cast<uint8_t*>(out.data()), &used, out.size()),
            LZMA_OK);
  out.resize(used);
  return out;
}

const char* kSquareObj = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n";

void expect_same_mesh(const Mesh& a, const Mesh& b) {
  EXPECT_EQ(a.positions, b.positions);
  EXPECT_EQ(a.normals, b.normals);
  EXPECT_EQ(a.colors, b.colors);
  EXPECT_EQ(a.texcoords, b.texcoords);
  EXPECT_EQ(a.indices, b.indices);
}

TEST(ImportCompressed, GzipAndXzGiveTheInnerFormat) {
  const Mesh plain = pms::load_mesh(write_file("pentagon.ply", kPentagonPly));
  expect_same_mesh(pms::load_mesh(write_file("pentagon.ply.gz", gzip(kPentagonPly))), plain);
  expect_same_mesh(pms::load_mesh(write_file("pentagon.PLY.XZ", xz(kPentagonPly))), plain);
  const Mesh square = pms::load_mesh(write_file("square.obj", kSquareObj));
  EXPECT_EQ(square.face_count(), 2u);
  expect_same_mesh(pms::load_mesh(write_file("square.obj.xz", xz(kSquareObj))), square);
  expect_same_mesh(pms::load_mesh_from_memory("square.obj.gz", to_bytes(gzip(kSquareObj))), square);
}

TEST(ImportCompressed, ConcatenatedGzipMembersAreOneFile) {
  const std::string text = kPentagonPly;
  const std::string two_members = gzip(text.substr(0, 100)) + gzip(text.substr(100));
  expect_same_mesh(pms::load_mesh(write_file("two.ply.gz", two_members)), pms::load_mesh(write_file("one.ply", text)));
}

TEST(ImportCompressed, OutputCapStopsDecompressionBombs) {
  const std::string zeros(1 << 20, '\0');
  for (const auto codec : {pms::Compression::gzip, pms::Compression::xz}) {
    const std::string packed = codec == pms::Compression::gzip ? gzip(zeros) : xz(zeros);
    const auto bytes = to_bytes(packed);
    const std::string message = error_of([&] { pms::decompress("bomb.gz", codec, bytes, {}, 4096); });
    EXPECT_EQ(message.rfind("bomb.gz: decompresses to more than 4096 bytes", 0), 0u) << message;
    EXPECT_EQ(pms::decompress("ok", codec, bytes, {}, zeros.size()).size(), zeros.size());
  }
}

TEST(ImportCompressed, TruncatedAndCorruptStreamsFail) {
  const std::string packed_gz = gzip(kPentagonPly), packed_xz = xz(kPentagonPly);
  expect_load_error(write_file("cut.ply.gz", packed_gz.substr(0, packed_gz.size() / 2)), "truncated gzip data");
  expect_load_error(write_file("cut.ply.xz", packed_xz.substr(0, packed_xz.size() / 2)), "xz data");
  expect_load_error(write_file("plain.ply.gz", kPentagonPly), "corrupt gzip data");
  expect_load_error(write_file("plain.ply.xz", kPentagonPly), "not xz data");
  expect_load_error(write_file("junk_after.ply.gz", packed_gz + "junk"), "after the end of the gzip stream");
}

// ---- errors ----------------------------------------------------------------------------------

TEST(ImportErrors, TruncatedBinaryPly) {
  const std::string ply = all_types_ply(false);
  expect_load_error(write_file("cut.ply", ply.substr(0, ply.size() - 3)), "truncated: the data ends in face 1 of 2");
  // Vertices take 300 bytes, then the skipped 'edge' records.
  const size_t header_end = ply.find("end_header\n") + 11;
  expect_load_error(write_file("cut_edges.ply", ply.substr(0, header_end + 310)),
                    "truncated: the data ends in edge 0 of 2");
}

TEST(ImportErrors, TruncatedAsciiPly) {
  std::string ply = kPentagonPly;
  ply.replace(ply.find("element face 1"), 14, "element face 2");
  expect_load_error(write_file("cut.ply", ply), "truncated: the data ends in face 1 of 2");
  expect_load_error(write_file("cut2.ply", std::string(kPentagonPly).substr(0, std::strlen(kPentagonPly) - 4)),
                    "truncated: the data ends in face 0 of 1");
}

TEST(ImportErrors, CountsThatCannotFitFailBeforeAllocating) {
  std::string lying =
      "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\n"
      "property float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
  lying.resize(200, '\x01');
  expect_load_error(write_file("lying.ply", lying), "declares 4000000000 vertex records");
  std::string ascii_faces = kPentagonPly;
  ascii_faces.replace(ascii_faces.find("element face 1"), 14, "element face 999999999999");
  expect_load_error(write_file("lying_faces.ply", ascii_faces), "declares 999999999999 face records");
  expect_load_error(write_file("lying.off", "OFF\n3000000000 1 0\n0 0 0\n"), "declares 3000000000 vertices");
}

TEST(ImportErrors, GarbageBytes) {
  std::string garbage(4096, '\0');
  uint32_t state = 12345;
  for (char& c : garbage) c = char((state = state * 1664525u + 1013904223u) >> 24);
  expect_load_error(write_file("garbage.ply", garbage), "not a PLY file");
  expect_load_error(write_file("garbage.off", garbage), "not an OFF file");
  expect_load_error(write_file("garbage.obj", garbage), "");
  expect_load_error(write_file("garbage.stl", garbage), "cannot read as .stl");
  expect_load_error(write_file("garbage.glb", garbage), "cannot read as .glb");
  expect_load_error(write_file("text.ply", "ply\nformat ascii 1.0\nelement vertex 1\nbogus line\n"),
                    "unknown PLY header keyword 'bogus'");
  expect_load_error(write_file("no_end.ply", "ply\nformat ascii 1.0\nelement vertex 1\n"), "no end_header");
}

TEST(ImportErrors, BadTokensNameTheLine) {
  std::string ply = kPentagonPly;
  ply.replace(ply.find("2 1 0"), 5, "2 x 0");
  expect_load_error(write_file("bad_token.ply", ply), "line 13: expected a number, found 'x'");
  expect_load_error(write_file("bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 zero\nf 1 2 3\n"),
                    "line 3: expected a vertex coordinate, found 'zero'");
  expect_load_error(write_file("bad.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 two\n"),
                    "line 6: expected a vertex index, found 'two'");
}

TEST(ImportErrors, IndexOutOfRange) {
  std::string ply = kPentagonPly;
  ply.replace(ply.find("5 0 1 2 3 4"), 11, "5 0 1 2 3 5");
  expect_load_error(write_file("range.ply", ply), "face 0: vertex index 5 out of range (5 vertices)");
  expect_load_error(write_file("range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n"), "uses vertex 3");
  expect_load_error(write_file("negative.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n"),
                    "face corner index -4 out of range");
  expect_load_error(write_file("zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n"), "face corner index 0");
  expect_load_error(write_file("range.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n"),
                    "vertex index 3 out of range");
}

TEST(ImportErrors, NonFiniteCoordinates) {
  std::string ply = kPentagonPly;
  ply.replace(ply.find("1 2 0"), 5, "1 nan 0");
  expect_load_error(write_file("nan.ply", ply), "vertex 3 has a NaN or infinite coordinate");
  expect_load_error(write_file("inf.obj", "v 0 0 0\nv 1 inf 0\nv 0 1 0\nf 1 2 3\n"),
                    "vertex 1 has a NaN or infinite coordinate");
  expect_load_error(write_file("huge.off", "OFF\n3 1 0\n0 0 1e39\n1 0 0\n0 1 0\n3 0 1 2\n"),
                    "vertex 0 has a NaN or infinite coordinate");
}

TEST(ImportErrors, NoFacesAndUnknownFormats) {
  std::string ply = kPentagonPly;
  ply.replace(ply.find("element face 1"), 14, "element face 0");
  expect_load_error(write_file("points.ply", ply.substr(0, ply.size() - 12)), "no faces");
  expect_load_error(write_file("points.obj", "v 0 0 0\nv 1 0 0\n"), "no faces");
  expect_load_error(write_file("mesh.notamesh", kPentagonPly), "unknown mesh format '.notamesh'");
  expect_load_error(write_file("mesh", kPentagonPly), "no file extension");
  expect_load_error((pms::test::temp_dir() / "missing.ply").string(), "cannot open");
  const std::string message = error_of([] { pms::load_mesh_from_memory("memory.xyzzy", to_bytes("abc")); });
  EXPECT_EQ(message, "memory.xyzzy: unknown mesh format '.xyzzy'");
}

// ---- the shared real scans -------------------------------------------------------------------

struct SharedModel {
  const char* file;
  size_t vertices;
  size_t faces;
  bool normals;
};

class ImportSharedModel : public testing::TestWithParam<SharedModel> {};

TEST_P(ImportSharedModel, HeaderCountsAndSaneGeometry) {
  const SharedModel& model = GetParam();
  PMS_REQUIRE_SHARED_MODEL(path, model.file);
  const Mesh mesh = pms::load_mesh(path.string());
  EXPECT_EQ(mesh.vertex_count(), model.vertices);
  EXPECT_EQ(mesh.face_count(), model.faces);
  EXPECT_EQ(mesh.has_normals(), model.normals);
  EXPECT_FALSE(mesh.has_colors());
  EXPECT_LT(*std::max_element(mesh.indices.begin(), mesh.indices.end()), mesh.vertex_count());
  // Normals are kept as stored (horse's are not unit length); none may be zero.
  for (size_t v = 0; model.normals && v < mesh.vertex_count(); ++v) {
    const float* n = &mesh.normals[v * 3];
    ASSERT_GT(n[0] * n[0] + n[1] * n[1] + n[2] * n[2], 0.0f) << "normal " << v;
  }
}

INSTANTIATE_TEST_SUITE_P(Models, ImportSharedModel,
                         testing::Values(SharedModel{"bunny.ply.xz", 35947, 69451, false},
                                         SharedModel{"horse.ply.xz", 48485, 96966, true},
                                         SharedModel{"feline.obj.xz", 49864, 99732, false},
                                         SharedModel{"skull.obj.xz", 40062, 80016, false},
                                         SharedModel{"dragon_res4.ply.xz", 5205, 11102, false}),
                         [](const testing::TestParamInfo<SharedModel>& info) {
                           std::string name = info.param.file;
                           return name.substr(0, name.find('.'));
                         });

TEST(ImportSharedModelValues, BunnyFirstVertexIsExact) {
  PMS_REQUIRE_SHARED_MODEL(path, "bunny.ply.xz");
  const Mesh mesh = pms::load_mesh(path.string());
  // The first body line is "-0.0378297 0.12794 0.00447467 0.850855 0.5".
  EXPECT_EQ(mesh.positions[0], -0.0378297f);
  EXPECT_EQ(mesh.positions[1], 0.12794f);
  EXPECT_EQ(mesh.positions[2], 0.00447467f);
}

TEST(ImportSharedModelValues, HorseFirstBinaryVertexIsExact) {
  PMS_REQUIRE_SHARED_MODEL(path, "horse.ply.xz");
  const Mesh mesh = pms::load_mesh(path.string());
  // Bits of the first 24-byte record, decoded independently (Python struct '<6f').
  const std::vector<float> first = {-0.002022000029683113f, -0.04017850011587143f, -0.0008630002848803997f,
                                    1.7324599027633667f,    -1.2141895294189453f,  6.249112129211426f};
  EXPECT_EQ(std::vector<float>(mesh.positions.begin(), mesh.positions.begin() + 3),
            std::vector<float>(first.begin(), first.begin() + 3));
  EXPECT_EQ(std::vector<float>(mesh.normals.begin(), mesh.normals.begin() + 3),
            std::vector<float>(first.begin() + 3, first.end()));
}

TEST(ImportSharedModelValues, ProgressReportsLoadFractionsInOrder) {
  PMS_REQUIRE_SHARED_MODEL(path, "bunny.ply.xz");
  std::vector<double> fractions;
  pms::load_mesh(path.string(), [&](std::string_view phase, double fraction) {
    EXPECT_EQ(phase, "load");
    fractions.push_back(fraction);
  });
  ASSERT_GE(fractions.size(), 4u);
  EXPECT_TRUE(std::is_sorted(fractions.begin(), fractions.end()));
  EXPECT_GE(fractions.front(), 0.0);
  EXPECT_EQ(fractions.back(), 1.0);
}

}  // namespace
