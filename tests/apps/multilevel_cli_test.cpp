// `pmstream multilevel` end to end (docs/cli.md, "multilevel"): build in both forms, info's per-level
// counts agree with the file, level writes the LOD (and a geomorph) as PLY, errors are one line.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <string>

#include "io/mesh.h"
#include "io/shapes.h"
#include "test_support.h"

namespace pms {
namespace {

TEST(MultilevelCli, BuildInfoLevelInBothForms) {
  const auto dir = test::temp_dir();
  Mesh input = make_torus(30, 12, 2.0f, 0.5f);
  input.colors.assign(input.vertex_count() * 4, 200);
  const std::string ply = (dir / "torus.ply").string();
  save_ply(input, ply);
  uint64_t binary_morph = 0;
  for (const bool ascii : {false, true}) {
    const std::string out = (dir / (ascii ? "torus.txt" : "torus.pml")).string();
    const test::CliRun build =
        test::run_pmstream("multilevel build " + ply + " -o " + out + " --levels 6 --json" + (ascii ? " --ascii" : ""));
    ASSERT_EQ(build.exit_code, 0) << build.err;
    const auto b = nlohmann::json::parse(build.out);
    EXPECT_EQ(b["levels"], 6);
    EXPECT_EQ(b["triangles"], input.face_count());
    EXPECT_EQ(b["attributes_dropped"], ascii);
    EXPECT_EQ(b["output_bytes"], std::filesystem::file_size(out));

    const test::CliRun info = test::run_pmstream("multilevel info " + out + " --json");
    ASSERT_EQ(info.exit_code, 0) << info.err;
    const auto j = nlohmann::json::parse(info.out);
    EXPECT_EQ(j["levels"], 6);
    EXPECT_EQ(j["representatives"], b["representatives"]);
    // The representatives only geomorphs use (merged levels may need some; this torus happens to need none,
    // GeomorphRepresentativesOfABuiltInModel has a model that does): the ASCII form leaves them out.
    EXPECT_EQ(j["geomorph_representatives"], b["geomorph_representatives"]);
    if (ascii) {
      EXPECT_EQ(j["geomorph_representatives"], 0);
      EXPECT_EQ(b["geomorph_representatives_dropped"], binary_morph);
    } else {
      binary_morph = j["geomorph_representatives"].get<uint64_t>();
      EXPECT_EQ(b["geomorph_representatives_dropped"], 0);
    }
    EXPECT_EQ(j["colors"], !ascii);
    ASSERT_EQ(j["per_level"].size(), 6u);
    uint64_t reps = 0;
    uint64_t compressed = 64;  // the compressed head
    for (const auto& row : j["per_level"]) {
      reps += row["representatives"].get<uint64_t>() + row["geomorph_representatives"].get<uint64_t>();
      compressed += row["compressed_bytes"].get<uint64_t>();
      const auto& bits = row["compressed_bits"];
      EXPECT_EQ(8 * row["compressed_bytes"].get<uint64_t>(),
                bits["header"].get<uint64_t>() + bits["representatives"].get<uint64_t>() +
                    bits["vertices"].get<uint64_t>() + bits["triangles"].get<uint64_t>());
    }
    EXPECT_EQ(reps, j["representatives"]);
    EXPECT_EQ(j["compressed_bytes"], compressed);
    EXPECT_EQ(j["position_bits"], 16);
    const auto& finest = j["per_level"].back();
    EXPECT_EQ(finest["level"], 0);
    EXPECT_EQ(finest["triangles"], input.face_count());
    const auto& coarsest = j["per_level"].front();

    const std::string lod = (dir / "lod.ply").string();
    const test::CliRun top = test::run_pmstream("multilevel level " + out + " --level 5 -o " + lod);
    ASSERT_EQ(top.exit_code, 0) << top.err;
    EXPECT_EQ(load_mesh(lod).face_count(), coarsest["triangles"].get<size_t>());
    const test::CliRun morph = test::run_pmstream("multilevel level " + out + " --level 0.5 -o " + lod);
    ASSERT_EQ(morph.exit_code, 0) << morph.err;
    const Mesh morphed = load_mesh(lod);
    EXPECT_EQ(morphed.face_count(), input.face_count()) << "a geomorph has the finer level's triangles";
    EXPECT_EQ(morphed.has_colors(), !ascii);
  }
  const test::CliRun beyond =
      test::run_pmstream("multilevel level " + (dir / "torus.pml").string() + " --level 6 -o x.ply");
  EXPECT_NE(beyond.exit_code, 0);
  EXPECT_NE(beyond.err.find("level 6 is outside 0..5"), std::string::npos) << beyond.err;
}

// Merged levels of the built-in terrain need representatives that only geomorphs use: the binary form
// keeps them, the ASCII form says how many it left out.
TEST(MultilevelCli, GeomorphRepresentativesOfABuiltInModel) {
  const auto dir = test::temp_dir();
  uint64_t kept = 0;
  for (const bool ascii : {false, true}) {
    const std::string out = (dir / (ascii ? "terrain.txt" : "terrain.pml")).string();
    const test::CliRun build = test::run_pmstream("multilevel build terrain:2000 -o " + out + " --levels 6 --json" +
                                                  (ascii ? " --ascii" : ""));
    ASSERT_EQ(build.exit_code, 0) << build.err;
    const auto b = nlohmann::json::parse(build.out);
    if (!ascii) {
      kept = b["geomorph_representatives"].get<uint64_t>();
      EXPECT_GT(kept, 0u);
    } else {
      EXPECT_EQ(b["geomorph_representatives"], 0);
      EXPECT_EQ(b["geomorph_representatives_dropped"], kept);
    }
    const test::CliRun info = test::run_pmstream("multilevel info " + out + " --json");
    ASSERT_EQ(info.exit_code, 0) << info.err;
    EXPECT_EQ(nlohmann::json::parse(info.out)["geomorph_representatives"], ascii ? 0 : kept);
  }
}

TEST(MultilevelCli, LevelOfARegion) {
  const auto dir = test::temp_dir();
  const Mesh input = make_torus(30, 12, 2.0f, 0.5f);
  const std::string ply = (dir / "torus.ply").string(), out = (dir / "torus.pml").string(),
                    lod = (dir / "r.ply").string();
  save_ply(input, ply);
  ASSERT_EQ(test::run_pmstream("multilevel build " + ply + " -o " + out + " --levels 6").exit_code, 0);
  const auto faces = [&](const std::string& args) {
    const test::CliRun run = test::run_pmstream("multilevel level " + out + " " + args + " -o " + lod);
    EXPECT_EQ(run.exit_code, 0) << args << ": " << run.err;
    return load_mesh(lod).face_count();
  };
  const size_t coarsest = faces("--level 5");
  EXPECT_EQ(faces("--region -3,-3,-3,3,3,3"), input.face_count());
  EXPECT_EQ(faces("--region -3,-3,-3,3,3,3 --level 2"), faces("--level 2"));
  EXPECT_EQ(faces("--region 10,10,10,11,11,11"), coarsest);
  const size_t half = faces("--region -3,-3,-3,0,3,3");
  EXPECT_GT(half, coarsest);
  EXPECT_LT(half, input.face_count());
  const size_t ball = faces("--sphere 2,0,0,0.8");
  EXPECT_GT(ball, coarsest);
  EXPECT_LT(ball, half);
  const test::CliRun no_level = test::run_pmstream("multilevel level " + out + " -o " + lod);
  EXPECT_NE(no_level.exit_code, 0);
  EXPECT_NE(no_level.err.find("--level is required"), std::string::npos) << no_level.err;
}

TEST(MultilevelCli, GridClusteringInput) {
  const auto dir = test::temp_dir();
  const std::string ply = (dir / "torus.ply").string(), out = (dir / "c.txt").string();
  save_ply(make_torus(40, 20, 2.0f, 0.5f), ply);
  const test::CliRun build =
      test::run_pmstream("multilevel build " + ply + " -o " + out + " --cluster grid:12,4 --ascii --json");
  ASSERT_EQ(build.exit_code, 0) << build.err;
  const auto b = nlohmann::json::parse(build.out);
  EXPECT_EQ(b["levels"], 3);
  EXPECT_EQ(b["clusterings"], 2);
  const test::CliRun info = test::run_pmstream("multilevel info " + out + " --json");
  ASSERT_EQ(info.exit_code, 0) << info.err;
  const auto j = nlohmann::json::parse(info.out);
  EXPECT_LT(j["per_level"][0]["triangles"].get<uint64_t>(), j["per_level"][1]["triangles"].get<uint64_t>());
  const test::CliRun bad =
      test::run_pmstream("multilevel build " + ply + " -o " + out + " --cluster grid:4,12 --ascii");
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.err.find("grid sizes must decrease"), std::string::npos) << bad.err;
}

// The paper's Fig. 12: two clusterings from a file give Fig. 6's three representatives.
TEST(MultilevelCli, ClusteringFileInput) {
  const auto dir = test::temp_dir();
  Mesh mesh;
  const float xy[10][2] = {{-3, 3},    {3, 3},        {-3, -3},  {3, -3},      {-2.3f, 3},
                           {-3, 2.3f}, {-2.3f, 2.3f}, {2.3f, 3}, {2.3f, 2.3f}, {3, 2.3f}};
  for (const auto& p : xy) mesh.positions.insert(mesh.positions.end(), {p[0], p[1], 0});
  mesh.indices = {6, 2, 8, 3, 8, 2, 4, 6, 7, 5, 2, 6, 6, 4, 5, 4, 0, 5, 8, 3, 9, 9, 1, 8, 7, 8, 1, 8, 7, 6};
  const std::string ply = (dir / "fig12.ply").string(), json = (dir / "fig12.json").string();
  save_ply(mesh, ply);
  nlohmann::json clusterings = nlohmann::json::array();
  for (const std::vector<uint32_t>& group : {std::vector<uint32_t>{1, 7, 8, 9}, std::vector<uint32_t>{0, 4, 5, 6}}) {
    std::vector<uint32_t> cluster(10);
    std::vector<float> positions(mesh.positions);
    for (uint32_t v = 0; v < 10; ++v) cluster[v] = v;
    for (uint32_t v : group) cluster[v] = 10;
    positions.insert(positions.end(), {group[0] == 1 ? 3.0f : -3.0f, 3.0f, 0.0f});
    clusterings.push_back({{"cluster", cluster}, {"positions", positions}});
  }
  {
    std::ofstream out(json);
    out << nlohmann::json{{"clusterings", clusterings}}.dump();
  }
  const std::string out = (dir / "fig12.txt").string();
  const test::CliRun build =
      test::run_pmstream("multilevel build " + ply + " -o " + out + " --cluster " + json + " --ascii --json");
  ASSERT_EQ(build.exit_code, 0) << build.err;
  const auto b = nlohmann::json::parse(build.out);
  EXPECT_EQ(b["levels"], 3);
  EXPECT_EQ(b["representatives"], 3) << "Fig. 12-13: three suffice";
  {
    std::ofstream bad(json);
    bad << R"({"clusterings": [{"cluster": [0, "x"], "positions": []}]})";
  }
  const test::CliRun refused =
      test::run_pmstream("multilevel build " + ply + " -o " + out + " --cluster " + json + " --ascii");
  EXPECT_NE(refused.exit_code, 0);
  EXPECT_NE(refused.err.find(json + ": not a clustering file"), std::string::npos) << refused.err;
}

// A textured input (u, v an affine function of x and y): the binary build keeps the texture coordinates,
// info reports them, level writes them as `s t` in the LOD and in a geomorph (blended with the positions,
// so still the same function of them); the ASCII build and the .pms build say they left them out.
TEST(MultilevelCli, TextureCoordinatesReachTheLevelPly) {
  const auto dir = test::temp_dir();
  Mesh input = make_torus(30, 12, 2.0f, 0.5f);
  const auto uv = [](const float* p, int k) { return 0.125f * p[k] + 0.5f; };
  for (size_t v = 0; v < input.vertex_count(); ++v)
    for (int k = 0; k < 2; ++k) input.texcoords.push_back(uv(&input.positions[3 * v], k));
  const std::string ply = (dir / "textured_torus.ply").string(), out = (dir / "textured_torus.pml").string();
  save_ply(input, ply);
  const test::CliRun build = test::run_pmstream("multilevel build " + ply + " -o " + out + " --levels 5 --json");
  ASSERT_EQ(build.exit_code, 0) << build.err;
  EXPECT_EQ(nlohmann::json::parse(build.out)["attributes_dropped"], false);
  const test::CliRun info = test::run_pmstream("multilevel info " + out + " --json");
  ASSERT_EQ(info.exit_code, 0) << info.err;
  const auto j = nlohmann::json::parse(info.out);
  EXPECT_EQ(j["texcoords"], true);
  EXPECT_EQ(j["texcoord_bits"], 16);
  EXPECT_NE(test::run_pmstream("multilevel info " + out).out.find(", texture coordinates"), std::string::npos);
  for (const char* level : {"0", "2", "2.5"}) {
    const std::string lod_path = (dir / (std::string("textured_lod_") + level + ".ply")).string();
    const test::CliRun lod = test::run_pmstream("multilevel level " + out + " --level " + level + " -o " + lod_path);
    ASSERT_EQ(lod.exit_code, 0) << lod.err;
    const Mesh got = load_mesh(lod_path);
    ASSERT_EQ(got.texcoords.size(), 2 * got.vertex_count()) << level;
    if (std::string(level) == "0") {
      EXPECT_EQ(got.vertex_count(), input.vertex_count());
    }
    for (size_t v = 0; v < got.vertex_count(); ++v)
      for (int k = 0; k < 2; ++k) ASSERT_NEAR(got.texcoords[2 * v + k], uv(&got.positions[3 * v], k), 1e-6f) << level;
  }
  const test::CliRun ascii =
      test::run_pmstream("multilevel build " + ply + " -o " + (dir / "textured.txt").string() + " --ascii");
  ASSERT_EQ(ascii.exit_code, 0) << ascii.err;
  EXPECT_NE(ascii.out.find("no normals, colours or texture coordinates"), std::string::npos) << ascii.out;
  const test::CliRun pms = test::run_pmstream("build " + ply + " -o " + (dir / "textured.pms").string() + " --json");
  ASSERT_EQ(pms.exit_code, 0) << pms.err;
  EXPECT_EQ(nlohmann::json::parse(pms.out)["texcoords_dropped"], true);
}

TEST(MultilevelCli, TerrainInputAndMalformedFiles) {
  const auto dir = test::temp_dir();
  const std::string out = (dir / "t.pml").string();
  const test::CliRun build = test::run_pmstream("multilevel build terrain:2000 -o " + out);
  ASSERT_EQ(build.exit_code, 0) << build.err;
  EXPECT_NE(build.out.find("levels:"), std::string::npos);
  const std::string bad = (dir / "bad.txt").string();
  {
    std::FILE* f = std::fopen(bad.c_str(), "w");
    std::fputs("#1-level\n{0, 0, 0}\n{0, 0}\n", f);
    std::fclose(f);
  }
  const test::CliRun info = test::run_pmstream("multilevel info " + bad);
  EXPECT_NE(info.exit_code, 0);
  EXPECT_NE(info.err.find(bad + ": line 3: a triangle of level 0 has 2 corners, not 3"), std::string::npos) << info.err;
}

}  // namespace
}  // namespace pms
