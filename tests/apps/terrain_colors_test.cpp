// The coloured terrain's colours reach the screen: built into a .pms, served on loopback and streamed in
// every mode, the viewer's mesh and its renderer buffers (what the page uploads) carry the input's colours.
#include <gtest/gtest.h>

#include <set>
#include <string>

#include "apps/build_pipeline.h"
#include "client/viewer.h"
#include "io/shapes.h"
#include "server/catalogue.h"
#include "server/http_server.h"
#include "server/tcp_server.h"
#include "test_support.h"

namespace pms {
namespace {

constexpr uint64_t kFaces = 20000;

std::set<uint32_t> colours_of(const std::vector<uint8_t>& rgba) {
  std::set<uint32_t> colours;
  for (size_t i = 0; i + 3 < rgba.size(); i += 4)
    colours.insert(uint32_t(rgba[i]) | uint32_t(rgba[i + 1]) << 8 | uint32_t(rgba[i + 2]) << 16 |
                   uint32_t(rgba[i + 3]) << 24);
  return colours;
}

// The colours of the vertices a triangle uses (slots not active yet hold white, and no triangle uses them).
std::set<uint32_t> colours_drawn(const client::MeshBuffers& buffers) {
  std::vector<uint8_t> used;
  for (size_t t = 0; t < buffers.triangle_count(); ++t) {
    const uint32_t* corner = &buffers.indices[3 * t];
    if (corner[0] == corner[1]) continue;  // a free slot
    for (int k = 0; k < 3; ++k)
      used.insert(used.end(), &buffers.colors[4 * size_t(corner[k])], &buffers.colors[4 * size_t(corner[k]) + 4]);
  }
  return colours_of(used);
}

// Low over one corner of the 10 km square, looking across it: near detail and far mountains.
Camera low_camera() {
  Camera c;
  c.eye[0] = 1500, c.eye[1] = 1500, c.eye[2] = 1800;
  c.target[0] = 6000, c.target[1] = 6000, c.target[2] = 300;
  c.up[0] = 0, c.up[1] = 0, c.up[2] = 1;
  c.width = 640;
  c.height = 360;
  return c;
}

TEST(TerrainColors, EveryModeShowsTheInputsColours) {
  const std::string pms_path = (test::temp_dir() / "terrain.pms").string();
  const std::string input = "terrain:" + std::to_string(kFaces) + ":colors";
  const app::BuildRun run = app::build_file(input, pms_path, BuildOptions{});
  EXPECT_EQ(run.stats.input_name, input);
  const std::set<uint32_t> input_colours = colours_of(make_terrain(kFaces, 1, TerrainColors::land).colors);

  const auto catalogue = server::Catalogue::open({pms_path});
  server::TcpServer tcp(catalogue, server::ServerLimits{}, "127.0.0.1", 0);
  server::HttpServer http(catalogue, server::HttpLimits{}, "127.0.0.1", 0);
  tcp.start();
  http.start();
  for (const char* mode : {"sender", "sender-plain", "vi", "dag", "receiver", "multilevel"}) {
    SCOPED_TRACE(mode);
    client::ViewerOptions options;
    options.mode = mode;
    const bool over_http = options.mode == "receiver" || options.mode == "multilevel";
    options.server =
        over_http ? "http://127.0.0.1:" + std::to_string(http.port()) : "127.0.0.1:" + std::to_string(tcp.port());
    const std::unique_ptr<client::Viewer> viewer = client::open_viewer(options, "terrain");
    viewer->frame(low_camera());
    const Mesh mesh = viewer->mesh();
    ASSERT_GT(mesh.vertex_count(), 100u);
    ASSERT_EQ(mesh.colors.size(), 4 * mesh.vertex_count());
    const std::set<uint32_t> shown = colours_of(mesh.colors);
    EXPECT_GT(shown.size(), 20u) << "a landscape, not one colour";
    for (uint32_t colour : shown)
      ASSERT_TRUE(input_colours.count(colour)) << "colour " << colour << " not in the input";
    const client::MeshBuffers& buffers = viewer->buffers();
    ASSERT_EQ(buffers.colors.size(), 4 * size_t(buffers.vertex_count()));
    const std::set<uint32_t> uploaded = colours_drawn(buffers);
    EXPECT_GT(uploaded.size(), 20u);
    for (uint32_t colour : uploaded) ASSERT_TRUE(input_colours.count(colour)) << "buffer colour " << colour;
  }
  http.stop();
  tcp.stop();
}

}  // namespace
}  // namespace pms
