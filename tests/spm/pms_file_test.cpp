// The .pms file (docs/pms-format.md, "Properties"): what is written is what is read, through mmap and from memory,
// and writing is all-or-nothing.
#include <gtest/gtest.h>
#include <algorithm>
#include <filesystem>
#include <fstream>

#include "common/error.h"
#include "pm_fixtures.h"
#include "spm/hierarchy.h"
#include "spm/pms_file.h"
#include "spm/vertex_id.h"
#include "test_support.h"

namespace pms {
namespace {

namespace fs = std::filesystem;

BuildStats sample_stats() {
  BuildStats s;
  s.input_name = "small.ply";
  s.tool_version = "0.1.0";
  s.options = "balanced base_vertices=3";
  s.input_vertices = 6;
  s.input_faces = 4;
  s.base_vertices = 3;
  s.base_faces = 1;
  s.vsplits = 3;
  s.tree_id_bits = 2;
  s.node_id_bits = 2;
  s.max_depth = 2;
  s.seconds = 0.125;
  s.clean_report = "nothing to clean";
  return s;
}

template <class A, class B>
void expect_same(const A& span, const B& vec, const char* what) {
  EXPECT_EQ(span.size(), vec.size()) << what;
  EXPECT_TRUE(std::equal(span.begin(), span.end(), vec.begin(), vec.end())) << what;
}

void expect_model_equals(const ModelData& m, const Hierarchy& h) {
  EXPECT_EQ(m.root_count, h.root_count);
  expect_same(m.base_faces, h.base_faces, "base_faces");
  expect_same(m.parent, h.parent, "parent");
  expect_same(m.first_child, h.first_child, "first_child");
  expect_same(m.position, h.position, "position");
  expect_same(m.cut_left, h.cut_left, "cut_left");
  expect_same(m.cut_right, h.cut_right, "cut_right");
  expect_same(m.refine, h.refine, "refine");
  expect_same(m.leaf_vertex, h.leaf_vertex, "leaf_vertex");
  expect_same(m.split_order, h.split_order, "split_order");
  expect_same(m.normals, h.normals, "normals");
  expect_same(m.colors, h.colors, "colors");
  expect_same(m.tree_id, h.tree_id, "tree_id");
  expect_same(m.node_id, h.node_id, "node_id");
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(m.bbox_min[k], h.bbox_min[k]);
    EXPECT_EQ(m.bbox_max[k], h.bbox_max[k]);
  }
  EXPECT_EQ(m.scale, h.scale);
  for (uint32_t n = 0; n < m.node_count(); ++n) EXPECT_EQ(m.find(m.id(n)), n);
}

void expect_stats_equal(const BuildStats& a, const BuildStats& b) {
  EXPECT_EQ(a.input_name, b.input_name);
  EXPECT_EQ(a.tool_version, b.tool_version);
  EXPECT_EQ(a.options, b.options);
  EXPECT_EQ(a.input_vertices, b.input_vertices);
  EXPECT_EQ(a.input_faces, b.input_faces);
  EXPECT_EQ(a.base_vertices, b.base_vertices);
  EXPECT_EQ(a.base_faces, b.base_faces);
  EXPECT_EQ(a.vsplits, b.vsplits);
  EXPECT_EQ(a.tree_id_bits, b.tree_id_bits);
  EXPECT_EQ(a.node_id_bits, b.node_id_bits);
  EXPECT_EQ(a.max_depth, b.max_depth);
  EXPECT_EQ(a.seconds, b.seconds);
  EXPECT_EQ(a.clean_report, b.clean_report);
}

std::vector<uint8_t> read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(PmsFile, RoundTripThroughMmapAndMemory) {
  for (const bool attributes : {true, false}) {
    const Hierarchy h = test::make_small_hierarchy(attributes);
    const BuildStats stats = sample_stats();
    const fs::path path = test::temp_dir() / "small.pms";
    write_pms(path.string(), h, stats);
    EXPECT_FALSE(fs::exists(path.string() + ".tmp"));

    const auto file = PmsFile::open(path.string());
    expect_model_equals(file->model(), h);
    expect_stats_equal(file->stats(), stats);
    EXPECT_EQ(file->file_size(), fs::file_size(path));

    const std::vector<uint8_t> bytes = read_bytes(path);
    const auto copy = PmsFile::from_bytes("small.pms", bytes.data(), bytes.size());
    expect_model_equals(copy->model(), h);
    expect_stats_equal(copy->stats(), stats);
    EXPECT_EQ(attributes, !copy->model().normals.empty());
  }
}

TEST(PmsFile, SectionsAreAlignedInTheMapping) {
  const fs::path path = test::temp_dir() / "small.pms";
  write_pms(path.string(), test::make_small_hierarchy(), sample_stats());
  const auto file = PmsFile::open(path.string());
  const ModelData& m = file->model();
  const auto base = reinterpret_cast<uintptr_t>(m.bbox_min) - 16;  // bbox_min sits 16 bytes into HEAD
  for (const void* p : {(const void*)m.parent.data(), (const void*)m.position.data(), (const void*)m.refine.data(),
                        (const void*)m.colors.data(), (const void*)m.base_faces.data()})
    EXPECT_EQ(reinterpret_cast<uintptr_t>(p) % 64, base % 64);
  EXPECT_EQ(base % 64, 0u) << "the mapping is page-aligned";
}

TEST(PmsFile, LargerForestRoundTrips) {
  Hierarchy h = test::make_forest(
      7, [](uint32_t tree, int depth, bool leftmost) { return depth < 6 + int(tree % 3) || (leftmost && depth < 20); });
  h.compute_ids();
  const fs::path path = test::temp_dir() / "forest.pms";
  write_pms(path.string(), h, {});
  const auto file = PmsFile::open(path.string());
  expect_model_equals(file->model(), h);
  EXPECT_EQ(file->stats().input_name, "");
}

TEST(PmsFile, OverwritesAtomically) {
  const fs::path path = test::temp_dir() / "model.pms";
  write_pms(path.string(), test::make_small_hierarchy(false), sample_stats());
  write_pms(path.string(), test::make_small_hierarchy(true), sample_stats());
  EXPECT_FALSE(PmsFile::open(path.string())->model().normals.empty());
  // A write that fails leaves the previous file untouched and no temporary behind.
  Hierarchy bad = test::make_small_hierarchy();
  bad.position.pop_back();
  const std::string message = error_of([&] { write_pms(path.string(), bad, {}); });
  EXPECT_NE(message.find(path.string() + ": refusing to write an invalid hierarchy: position has 26 values"),
            std::string::npos)
      << message;
  EXPECT_FALSE(fs::exists(path.string() + ".tmp"));
  EXPECT_NO_THROW(PmsFile::open(path.string()));
}

TEST(PmsFile, UnwritableDirectoryIsAClearError) {
  const fs::path path = test::temp_dir() / "no" / "such" / "dir" / "model.pms";
  const std::string message = error_of([&] { write_pms(path.string(), test::make_small_hierarchy(), {}); });
  EXPECT_EQ(message.rfind(path.string() + ": cannot create " + path.string() + ".tmp: ", 0), 0u) << message;
  EXPECT_FALSE(fs::exists(path.parent_path()));
}

// The writer runs the reader's validation: no file the reader would reject is ever written.
TEST(PmsFile, WriterRejectsInvalidStructure) {
  Hierarchy too_deep =
      test::make_forest(2, [](uint32_t tree, int depth, bool leftmost) { return tree == 0 && leftmost && depth < 64; });
  const fs::path dir = test::temp_dir();
  std::string message = error_of([&] { write_pms((dir / "deep.pms").string(), too_deep, {}); });
  EXPECT_NE(message.find("section CHLD: node"), std::string::npos) << message;
  EXPECT_NE(message.find("deeper than 63 levels"), std::string::npos) << message;

  // Roots 0, 1, 2; 0 -> 3, 4; 3 -> 5, 6; 1 -> 7, 8: depth 2 before depth 1.
  Hierarchy h = test::make_small_hierarchy(false);
  h.parent = {kNone, kNone, kNone, 0, 0, 3, 3, 1, 1};
  h.first_child = {3, 7, kNone, 5, kNone, kNone, kNone, kNone, kNone};
  h.cut_left = {2, 2, kNone, 2, kNone, kNone, kNone, kNone, kNone};
  h.cut_right.assign(9, kNone);
  h.leaf_vertex = {kNone, kNone, 0, kNone, 1, 2, 3, 4, 5};
  h.split_order = {0, 1, 3};
  message = error_of([&] { write_pms((dir / "bfs.pms").string(), h, {}); });
  EXPECT_NE(message.find("section PRNT: node 7 at depth 1 follows a node at depth 2"), std::string::npos) << message;
  EXPECT_TRUE(fs::is_empty(dir));
}

TEST(PmsFile, OpenErrorsNameTheFile) {
  const fs::path dir = test::temp_dir();
  EXPECT_EQ(error_of([&] {
              PmsFile::open((dir / "missing.pms").string());
            }).rfind((dir / "missing.pms").string() + ": cannot open: ", 0),
            0u);
  EXPECT_EQ(error_of([&] { PmsFile::open(dir.string()); }), dir.string() + ": not a regular file");
  std::ofstream((dir / "empty.pms").string()).close();
  EXPECT_EQ(error_of([&] { PmsFile::open((dir / "empty.pms").string()); }),
            (dir / "empty.pms").string() + ": header: file is 0 bytes, shorter than the 40-byte header");
  EXPECT_EQ(error_of([&] { PmsFile::from_bytes("null", nullptr, 0); }),
            "null: header: file is 0 bytes, shorter than the 40-byte header");
}

}  // namespace
}  // namespace pms
