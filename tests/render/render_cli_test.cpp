// `pmstream render` and `pmstream compare` end to end (docs/cli.md): PNG size and content, the JSON
// fields, .pms input rendering the finest mesh, and one-line errors naming the file.
#include <gtest/gtest.h>
#include <png.h>
#include <sys/wait.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <fstream>
#include <string>

#include "io/mesh.h"
#include "io/shapes.h"
#include "render/render.h"
#include "test_support.h"

namespace pms {
namespace {

using RunResult = test::CliRun;
RunResult run(const std::string& args) { return test::run_pmstream(args); }

void expect_one_line_error(const RunResult& r, const std::string& names) {
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find(names), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
}

Image read_png(const std::string& path) {
  png_image png{};
  png.version = PNG_IMAGE_VERSION;
  Image image;
  if (!png_image_begin_read_from_file(&png, path.c_str())) {
    ADD_FAILURE() << path << ": " << png.message;
    return image;
  }
  png.format = PNG_FORMAT_RGB;
  image.width = png.width, image.height = png.height;
  image.rgb.resize(PNG_IMAGE_SIZE(png));
  if (!png_image_finish_read(&png, nullptr, image.rgb.data(), 0, nullptr)) ADD_FAILURE() << path << ": " << png.message;
  return image;
}

struct Scene {
  std::filesystem::path dir = test::temp_dir();
  std::string fine = (dir / "fine.ply").string(), coarse = (dir / "coarse.ply").string();
  std::string camera = (dir / "cam.json").string();

  Scene() {
    save_ply(make_sphere(24, 48), fine);
    save_ply(make_sphere(6, 12), coarse);
    std::ofstream(camera)
        << R"({"eye":[0.5,0.8,3],"target":[0,0,0],"up":[0,1,0],"fovy_deg":40,"width":80,"height":60})";
  }
};

TEST(RenderCli, WritesThePngAtTheCameraOrGivenSize) {
  Scene scene;
  const std::string png = (scene.dir / "out.png").string();
  const RunResult r = run("render " + scene.fine + " --camera " + scene.camera + " -o " + png);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Image image = read_png(png);
  ASSERT_EQ(image.width, 80u);
  ASSERT_EQ(image.height, 60u);
  const RenderOptions defaults;
  auto is_background = [&](uint32_t x, uint32_t y) {
    const uint8_t* p = &image.rgb[3 * (size_t(y) * image.width + x)];
    return p[0] == defaults.background[0] && p[1] == defaults.background[1] && p[2] == defaults.background[2];
  };
  EXPECT_FALSE(is_background(40, 30));  // the sphere in the middle
  EXPECT_TRUE(is_background(0, 0));

  const RunResult sized =
      run("render " + scene.fine + " --camera " + scene.camera + " -o " + png + " --width 33 --height 21");
  ASSERT_EQ(sized.exit_code, 0) << sized.err;
  const Image small = read_png(png);
  EXPECT_EQ(small.width, 33u);
  EXPECT_EQ(small.height, 21u);
}

TEST(RenderCli, CompareReportsTheMetrics) {
  Scene scene;
  const RunResult same = run("compare " + scene.fine + " " + scene.fine + " --camera " + scene.camera + " --json");
  ASSERT_EQ(same.exit_code, 0) << same.err;
  const auto identical = nlohmann::json::parse(same.out);
  EXPECT_EQ(identical["psnr"].get<double>(), kPsnrIdenticalJson);
  EXPECT_EQ(identical["error_pixels"].get<uint64_t>(), 0u);
  EXPECT_EQ(identical["error_fraction"].get<double>(), 0.0);
  const RunResult same_text = run("compare " + scene.fine + " " + scene.fine + " --camera " + scene.camera);
  ASSERT_EQ(same_text.exit_code, 0) << same_text.err;
  EXPECT_NE(same_text.out.find("inf"), std::string::npos) << same_text.out;

  const RunResult differ = run("compare " + scene.fine + " " + scene.coarse + " --camera " + scene.camera + " --json");
  ASSERT_EQ(differ.exit_code, 0) << differ.err;
  const auto m = nlohmann::json::parse(differ.out);
  EXPECT_GT(m["psnr"].get<double>(), 5.0);
  EXPECT_LT(m["psnr"].get<double>(), 60.0);
  EXPECT_GT(m["error_pixels"].get<uint64_t>(), 0u);
  EXPECT_NEAR(m["error_fraction"].get<double>(), m["error_pixels"].get<double>() / (80.0 * 60.0), 1e-12);
  // Symmetric: the same view for both (near/far from the union of the boxes).
  const RunResult reverse = run("compare " + scene.coarse + " " + scene.fine + " --camera " + scene.camera + " --json");
  ASSERT_EQ(reverse.exit_code, 0) << reverse.err;
  EXPECT_EQ(nlohmann::json::parse(reverse.out), m);
}

TEST(RenderCli, PmsRendersItsFinestMesh) {
  Scene scene;
  const std::string pms_path = (scene.dir / "fine.pms").string();
  const RunResult build = run("build " + scene.fine + " -o " + pms_path);
  ASSERT_EQ(build.exit_code, 0) << build.err;
  const std::string png = (scene.dir / "pms.png").string();
  const RunResult r = run("render " + pms_path + " --camera " + scene.camera + " -o " + png);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(read_png(png).width, 80u);
  // Same triangles as the input (renumbered): at most rounding of the normal sums differs.
  const RunResult c = run("compare " + scene.fine + " " + pms_path + " --camera " + scene.camera + " --json");
  ASSERT_EQ(c.exit_code, 0) << c.err;
  const auto m = nlohmann::json::parse(c.out);
  EXPECT_GT(m["psnr"].get<double>(), 45.0) << c.out;
  EXPECT_LT(m["error_fraction"].get<double>(), 0.01) << c.out;
}

TEST(RenderCli, BadInputsFailWithOneLineNamingTheFile) {
  Scene scene;
  const std::string png = (scene.dir / "out.png").string();
  const std::string missing_camera = (scene.dir / "nope.json").string();
  expect_one_line_error(run("render " + scene.fine + " --camera " + missing_camera + " -o " + png), missing_camera);

  const std::string bad_json = (scene.dir / "bad.json").string();
  std::ofstream(bad_json) << "{\"eye\": [0, 0, 3], \"target\": ";
  expect_one_line_error(run("render " + scene.fine + " --camera " + bad_json + " -o " + png), bad_json);
  expect_one_line_error(run("compare " + scene.fine + " " + scene.fine + " --camera " + bad_json), bad_json);

  const std::string degenerate = (scene.dir / "degenerate.json").string();
  std::ofstream(degenerate) << R"({"eye":[1,1,1],"target":[1,1,1]})";
  expect_one_line_error(run("render " + scene.fine + " --camera " + degenerate + " -o " + png), degenerate);

  const std::string corrupt = (scene.dir / "corrupt.ply").string();
  std::ofstream(corrupt) << "ply\nformat binary_little_endian 1.0\nelement vertex 1000\nproperty float x\n"
                            "property float y\nproperty float z\nend_header\nshort";
  expect_one_line_error(run("render " + corrupt + " --camera " + scene.camera + " -o " + png), corrupt);
  expect_one_line_error(run("compare " + scene.fine + " " + corrupt + " --camera " + scene.camera + " --json"),
                        corrupt);

  const std::string corrupt_pms = (scene.dir / "corrupt.pms").string();
  std::ofstream(corrupt_pms) << "this is not a pms file at all, just text that is long enough to look at";
  expect_one_line_error(run("render " + corrupt_pms + " --camera " + scene.camera + " -o " + png), corrupt_pms);

  const std::string missing_mesh = (scene.dir / "missing.ply").string();
  expect_one_line_error(run("compare " + missing_mesh + " " + scene.fine + " --camera " + scene.camera), missing_mesh);

  const std::string unwritable = (scene.dir / "no-such-dir" / "out.png").string();
  expect_one_line_error(run("render " + scene.fine + " --camera " + scene.camera + " -o " + unwritable), unwritable);
}

}  // namespace
}  // namespace pms
