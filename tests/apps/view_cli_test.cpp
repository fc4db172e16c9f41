// `pmstream path` and `pmstream refine --camera` end to end (docs/cli.md contracts): PATH.json and CAM.json
// fields, deterministic paths with the geometry each kind promises, refine --camera JSON fields and a mesh
// that matches them, and one-line errors with a non-zero exit code for bad inputs.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <string>

#include "io/mesh.h"
#include "io/shapes.h"
#include "test_support.h"

namespace pms {
namespace {

std::string slurp(const std::string& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

using RunResult = test::CliRun;
RunResult run(const std::string& args) { return test::run_pmstream(args); }

// A torus built once per test (flat: its up axis is z).
struct Model {
  std::filesystem::path dir = test::temp_dir();
  std::string pms = (dir / "torus.pms").string();
  size_t input_faces = 0, base_faces = 0, base_vertices = 0;
  Model() {
    const Mesh input = make_torus(48, 20, 2.0f, 0.5f);
    input_faces = input.face_count();
    const std::string ply = (dir / "torus.ply").string();
    save_ply(input, ply);
    const RunResult build = run("build " + ply + " -o " + pms + " --json");
    EXPECT_EQ(build.exit_code, 0) << build.err;
    const auto stats = nlohmann::json::parse(build.out);
    base_faces = stats["base_faces"].get<size_t>();
    base_vertices = stats["base_vertices"].get<size_t>();
  }
};

float distance(const nlohmann::json& a, const nlohmann::json& b) {
  float d2 = 0;
  for (int k = 0; k < 3; ++k) d2 += (a[k].get<float>() - b[k].get<float>()) * (a[k].get<float>() - b[k].get<float>());
  return std::sqrt(d2);
}

TEST(ViewCli, PathsAreDeterministicAndShapedAsTheirKind) {
  const Model model;
  for (const std::string kind : {"orbit", "scan", "zoom", "look", "rotate"}) {
    SCOPED_TRACE(kind);
    const std::string a = (model.dir / (kind + "-a.json")).string(), b = (model.dir / (kind + "-b.json")).string();
    const std::string options = " --model " + model.pms + " --frames 24 --width 640 --height 480 --fovy 50 -o ";
    const RunResult first = run("path " + kind + options + a);
    ASSERT_EQ(first.exit_code, 0) << first.err;
    ASSERT_EQ(run("path " + kind + options + b).exit_code, 0);
    EXPECT_EQ(slurp(a), slurp(b)) << "not deterministic";
    const auto path = nlohmann::json::parse(slurp(a));
    const auto& frames = path["frames"];
    ASSERT_EQ(frames.size(), 24u);
    for (const auto& cam : frames) {
      for (const char* field : {"eye", "target", "up"}) ASSERT_EQ(cam[field].size(), 3u) << field;
      EXPECT_EQ(cam["fovy_deg"].get<float>(), 50.0f);
      EXPECT_EQ(cam["width"], 640);
      EXPECT_EQ(cam["height"], 480);
      EXPECT_EQ(cam["up"][2], 1.0f) << "a flat model is seen with z up";
    }
    if (kind == "orbit") {  // a circle around a fixed centre that frames the torus (radius ~2.6)
      const float r = distance(frames[0]["eye"], frames[0]["target"]);
      EXPECT_GT(r, 2.6f);
      for (const auto& cam : frames) {
        EXPECT_NEAR(distance(cam["eye"], cam["target"]), r, 1e-3f * r);
        EXPECT_EQ(cam["target"], frames[0]["target"]);
      }
      EXPECT_GT(distance(frames[0]["eye"], frames[12]["eye"]), 1.9f * r * std::cos(20 * 3.14159f / 180));
    } else if (kind == "scan") {  // rising from the bottom of the box (z = -0.5) to the top (0.5)
      EXPECT_NEAR(frames[0]["target"][2].get<float>(), -0.5f, 1e-3f);
      EXPECT_NEAR(frames[23]["target"][2].get<float>(), 0.5f, 1e-3f);
      for (size_t i = 1; i < frames.size(); ++i)
        EXPECT_GT(frames[i]["eye"][2].get<float>(), frames[i - 1]["eye"][2].get<float>());
      for (const auto& cam : frames) {  // just outside the box (half extents 2.5 x 2.5), a third of its height away
        EXPECT_GT(distance(cam["eye"], cam["target"]), 2.5f);
        EXPECT_LT(distance(cam["eye"], cam["target"]), 0.5f * (2.5f + 2.5f) * 1.42f + 0.4f) << "close to the surface";
      }
    } else if (kind == "look") {  // the orbit's distance around a fixed centre, from 60° above to 60° below
      const float r = distance(frames[0]["eye"], frames[0]["target"]);
      EXPECT_GT(r, 2.6f);
      const float z0 = frames[0]["target"][2].get<float>(), sin60 = std::sin(60 * 3.14159f / 180);
      EXPECT_NEAR(frames[0]["eye"][2].get<float>() - z0, r * sin60, 1e-3f * r) << "starts at the top";
      EXPECT_NEAR(frames[23]["eye"][2].get<float>() - z0, -r * sin60, 1e-3f * r) << "ends at the bottom";
      for (size_t i = 1; i < frames.size(); ++i) {
        EXPECT_NEAR(distance(frames[i]["eye"], frames[i]["target"]), r, 1e-3f * r);
        EXPECT_EQ(frames[i]["target"], frames[0]["target"]);
        EXPECT_LT(frames[i]["eye"][2].get<float>(), frames[i - 1]["eye"][2].get<float>());
      }
    } else if (kind == "rotate") {  // in from the orbit's distance, circling faster and faster (z up)
      EXPECT_GT(distance(frames[0]["eye"], frames[0]["target"]), 2.6f);
      for (size_t i = 8; i < frames.size(); ++i)  // from a third of the way on: just outside the box
        EXPECT_LT(distance(frames[i]["eye"], frames[i]["target"]), 0.5f * (2.5f + 2.5f) * 1.42f + 0.4f) << i;
      const auto azimuth = [&](size_t i) {
        const auto& c = frames[i];
        return std::atan2(c["eye"][1].get<float>() - c["target"][1].get<float>(),
                          c["eye"][0].get<float>() - c["target"][0].get<float>());
      };
      float last_step = 0;
      for (size_t i = 1; i < frames.size(); ++i) {
        float step = azimuth(i) - azimuth(i - 1);
        if (step < -3.14159f) step += 2 * 3.14159f;
        EXPECT_GT(step, last_step) << "frame " << i << ": not faster than the frame before";
        last_step = step;
      }
    } else {  // from far to a close-up, always getting closer
      EXPECT_GT(distance(frames[0]["eye"], frames[0]["target"]), 10.0f);
      EXPECT_LT(distance(frames[23]["eye"], frames[23]["target"]), 0.2f);
      for (size_t i = 1; i < frames.size(); ++i)
        EXPECT_LT(distance(frames[i]["eye"], frames[i]["target"]),
                  distance(frames[i - 1]["eye"], frames[i - 1]["target"]));
    }
  }
}

TEST(ViewCli, RefineForACamera) {
  const Model model;
  const std::string path = (model.dir / "orbit.json").string(), cam = (model.dir / "cam.json").string();
  ASSERT_EQ(run("path zoom --model " + model.pms + " --frames 5 -o " + path).exit_code, 0);
  std::ofstream(cam) << nlohmann::json::parse(slurp(path))["frames"][2].dump();

  size_t previous_faces = SIZE_MAX;
  for (const std::string tolerance : {"0", "1", "8"}) {
    SCOPED_TRACE("tolerance " + tolerance);
    const std::string out = (model.dir / ("view-" + tolerance + ".ply")).string();
    const RunResult r =
        run("refine " + model.pms + " --camera " + cam + " --tolerance " + tolerance + " -o " + out + " --json");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto stats = nlohmann::json::parse(r.out);
    for (const char* field : {"vertices", "faces", "vsplits_applied", "seconds"})
      EXPECT_TRUE(stats.contains(field)) << field;
    const Mesh mesh = load_mesh(out);
    EXPECT_EQ(stats["faces"].get<size_t>(), mesh.face_count());
    EXPECT_EQ(stats["vertices"].get<size_t>(), mesh.vertex_count());
    EXPECT_EQ(stats["vsplits_applied"].get<size_t>() + model.base_vertices, mesh.vertex_count());
    EXPECT_GT(mesh.face_count(), model.base_faces);
    EXPECT_LT(mesh.face_count(), model.input_faces) << "half the torus faces away";
    EXPECT_LE(mesh.face_count(), previous_faces) << "a larger tolerance never refines more";
    previous_faces = mesh.face_count();
  }
  // --tolerance defaults to 1 pixel.
  const RunResult fallback =
      run("refine " + model.pms + " --camera " + cam + " -o " + (model.dir / "d.ply").string() + " --json");
  ASSERT_EQ(fallback.exit_code, 0) << fallback.err;
  const RunResult one = run("refine " + model.pms + " --camera " + cam + " --tolerance 1 -o " +
                            (model.dir / "e.ply").string() + " --json");
  EXPECT_EQ(nlohmann::json::parse(fallback.out)["faces"], nlohmann::json::parse(one.out)["faces"]);
}

void expect_one_line_error(const RunResult& r, const std::string& mentions) {
  EXPECT_NE(r.exit_code, 0);
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_NE(r.err.find(mentions), std::string::npos) << r.err;
}

TEST(ViewCli, BadInputsGiveOneLineErrors) {
  const Model model;
  const std::string cam = (model.dir / "cam.json").string(), out = (model.dir / "o.ply").string();
  std::ofstream(cam) << R"({"eye":[0,0,8],"target":[0,0,0],"up":[0,1,0],"fovy_deg":45,"width":320,"height":240})";
  const std::string refine = "refine " + model.pms + " -o " + out;
  expect_one_line_error(run(refine + " --full --camera " + cam), "exactly one");
  expect_one_line_error(run(refine), "exactly one");
  expect_one_line_error(run(refine + " --splits 3 --tolerance 2"), "--tolerance");
  expect_one_line_error(run(refine + " --camera " + cam + " --tolerance=-1"), "--tolerance");
  const std::string missing = (model.dir / "missing.json").string();
  expect_one_line_error(run(refine + " --camera " + missing), missing);
  const std::string broken = (model.dir / "broken.json").string();
  std::ofstream(broken) << R"({"eye":[0,0,8],"target":[0,0,8]})";
  expect_one_line_error(run(refine + " --camera " + broken), "eye and target");
  std::ofstream(broken) << R"({"eye":[0,0,8],"target":)";
  expect_one_line_error(run(refine + " --camera " + broken), broken);

  const std::string path = "path orbit --model " + model.pms + " -o " + (model.dir / "p.json").string();
  expect_one_line_error(run("path spiral --model " + model.pms + " --frames 3 -o " + (model.dir / "p.json").string()),
                        "spiral");
  expect_one_line_error(run(path + " --frames 0"), "--frames");
  expect_one_line_error(run(path + " --frames 3 --fovy 200"), "--fovy");
  expect_one_line_error(run(path + " --frames 3 --width 0"), "--width");
  const std::string no_model = (model.dir / "nope.pms").string();
  expect_one_line_error(run("path scan --model " + no_model + " --frames 3 -o " + (model.dir / "p.json").string()),
                        no_model);
  EXPECT_FALSE(std::filesystem::exists(model.dir / "p.json"));
}

}  // namespace
}  // namespace pms
