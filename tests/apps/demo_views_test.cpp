// The demo's views: over a terrain the page opens beyond its edge looking across it (above every peak,
// the land ahead), the snapshots get a sun and a sky; any other model keeps the orbit and the headlight.
#include <gtest/gtest.h>

#include <string>

#include "apps/build_pipeline.h"
#include "apps/camera_path.h"
#include "apps/demo_views.h"
#include "io/shapes.h"
#include "spm/pms_file.h"
#include "test_support.h"

namespace pms {
namespace {

std::unique_ptr<PmsFile> built(const std::string& input, const std::string& name) {
  const std::string path = (test::temp_dir() / (name + ".pms")).string();
  app::build_file(input, path, BuildOptions{});
  return PmsFile::open(path);
}

TEST(DemoViews, TheTerrainIsSeenAcrossFromBeyondItsEdge) {
  const auto file = built("terrain:5000:colors", "terrain");
  const ModelData& m = file->model();
  const Camera c = app::demo_first_view(m);
  EXPECT_EQ(c.up[0], 0.0f);
  EXPECT_EQ(c.up[1], 0.0f);
  EXPECT_EQ(c.up[2], 1.0f) << "the terrain's heights are z";
  EXPECT_GT(c.eye[2], m.bbox_max[2]) << "above every peak";
  EXPECT_LT(c.eye[0], m.bbox_min[0]) << "beyond the near edge";
  for (int k = 0; k < 2; ++k) {
    EXPECT_GT(c.target[k], m.bbox_min[k]);
    EXPECT_LT(c.target[k], m.bbox_max[k]) << "looking at the land, axis " << k;
  }
  EXPECT_LT(c.target[2], c.eye[2]) << "looking down";
  EXPECT_EQ(app::demo_flight_path(m, 7).size(), 7u);
  const RenderOptions look = app::demo_snapshot_look(m);
  EXPECT_LT(look.light[2], 0.0f) << "a sun shining down";
  EXPECT_NE(look.background[2], RenderOptions{}.background[2]) << "a sky";
}

TEST(DemoViews, AnyOtherModelIsOrbitedUnderTheHeadlight) {
  const std::string ply = (test::temp_dir() / "torus.ply").string();
  save_ply(make_torus(24, 12, 2.0f, 0.8f), ply);
  const auto file = built(ply, "torus");
  const ModelData& m = file->model();
  app::PathOptions options;
  options.frames = 1;
  const Camera orbit = app::make_camera_path(app::PathKind::orbit, m, options).front();
  const Camera c = app::demo_first_view(m);
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(c.eye[k], orbit.eye[k]);
    EXPECT_EQ(c.target[k], orbit.target[k]);
  }
  const RenderOptions look = app::demo_snapshot_look(m);
  for (int k = 0; k < 3; ++k) EXPECT_EQ(look.light[k], 0.0f) << "the headlight";
}

}  // namespace
}  // namespace pms
