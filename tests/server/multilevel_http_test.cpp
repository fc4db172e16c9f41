// The multilevel mode over real loopback HTTP: `serve` offers a .pml file as a head and one resource per
// level; the client loads the levels coarsest first, adding each as it arrives, and after the last one
// holds exactly the file's structure; a budget stops it at the LOD it needs; hostile URLs get 4xx.
#include <gtest/gtest.h>
#include <algorithm>
#include <string>

#include "builder/build.h"
#include "client/multilevel_client.h"
#include "common/error.h"
#include "http_test_client.h"
#include "io/shapes.h"
#include "multilevel/build.h"
#include "multilevel/codec.h"
#include "multilevel/file.h"
#include "multilevel/mesh.h"
#include "server/catalogue.h"
#include "streaming_fixture.h"
#include "server/http_server.h"
#include "test_support.h"

namespace pms {
namespace {

struct MultilevelModel {
  std::string path;
  MultilevelMesh mesh;  // as read back from the file
};

const MultilevelModel& sphere_model() {
  static const MultilevelModel model = [] {
    // With texture coordinates (a planar projection), so that both forms carry a per-vertex attribute.
    Mesh mesh = make_sphere(40, 60);
    for (size_t v = 0; v < mesh.vertex_count(); ++v)
      mesh.texcoords.insert(mesh.texcoords.end(),
                            {0.5f + 0.5f * mesh.positions[3 * v], 0.5f + 0.5f * mesh.positions[3 * v + 1]});
    const BuildResult built = build_progressive_mesh(mesh);
    MultilevelModel m;
    m.path = (test::temp_dir() / "ball.pml").string();
    write_multilevel(m.path, build_multilevel(mesh, collapses_of(built.hierarchy), 12), false);
    m.mesh = read_multilevel(m.path);
    return m;
  }();
  return model;
}

struct Server : test::LoopbackHttpServer {
  Server() : LoopbackHttpServer(server::Catalogue::open({sphere_model().path})) {}
};

// /models/ball/VERSION: where the served file's resources are.
const std::string& ball() {
  static const std::string url = test::model_url(*server::Catalogue::open({sphere_model().path}), "ball");
  return url;
}

Camera far_camera() {
  Camera c;
  c.eye[2] = 1000;
  return c;
}

// Every level, in either form: the plain levels give the file's structure exactly, the compressed ones the
// same structure with its positions on the server's grid.
void expect_every_level_arrives(bool compressed) {
  const MultilevelModel& model = sphere_model();
  const MultilevelMesh want = compressed ? snapped_multilevel(model.mesh, kDefaultPositionBits) : model.mesh;
  Server server;
  client::MultilevelOptions options;
  options.budget = uint64_t(1) << 40;  // every level
  options.compressed = compressed;
  client::MultilevelClient client(server.url(), options);
  ASSERT_EQ(client.list(), std::vector<std::string>{"ball"});
  client.open("ball");
  const client::MultilevelFrame frame = client.frame(far_camera());
  const uint32_t levels = model.mesh.level_count();
  ASSERT_GE(levels, 4u);
  ASSERT_EQ(client.arrivals().size(), levels);
  for (uint32_t i = 0; i < levels; ++i) EXPECT_EQ(client.arrivals()[i].level, levels - 1 - i) << "arrival " << i;
  for (uint32_t i = 1; i < levels; ++i) EXPECT_GT(client.arrivals()[i].down_bytes, client.arrivals()[i - 1].down_bytes);
  EXPECT_EQ(frame.report.vsplits, levels);
  EXPECT_EQ(frame.wanted_level, 0u);
  EXPECT_EQ(frame.report.faces, model.mesh.faces());
  ASSERT_TRUE(client.loader().complete());
  const MultilevelMesh& got = client.mesh();
  EXPECT_EQ(got.positions, want.positions);
  ASSERT_FALSE(want.texcoords.empty());
  EXPECT_EQ(got.texcoords, want.texcoords);
  EXPECT_EQ(got.triangles, want.triangles);
  EXPECT_EQ(got.representative, want.representative);
  EXPECT_EQ(got.vertex_count, want.vertex_count);
  EXPECT_EQ(got.triangle_count, want.triangle_count);
  const uint64_t requests = server.http.stats().requests.load();
  client.frame(far_camera());
  EXPECT_EQ(server.http.stats().requests.load(), requests) << "a loaded model asks for nothing more";
}

TEST(MultilevelHttp, CompressedLevelsArriveCoarsestFirstAndTheLastGivesTheMeshOnTheGrid) {
  expect_every_level_arrives(true);
}

TEST(MultilevelHttp, PlainLevelsArriveCoarsestFirstAndTheLastGivesTheFilesMesh) { expect_every_level_arrives(false); }

// A budget stops the load at the finest LOD within it, and that LOD is usable and already the file's.
TEST(MultilevelHttp, ABudgetLoadsOnlyTheLevelsItNeedsAndTheirLodIsTheFiles) {
  const MultilevelModel& model = sphere_model();
  const uint32_t levels = model.mesh.level_count(), wanted = levels / 2;
  Server server;
  client::MultilevelOptions options;
  options.budget = model.mesh.triangle_count[wanted];
  client::MultilevelClient client(server.url(), options);
  client.open("ball");
  const client::MultilevelFrame frame = client.frame(far_camera());
  EXPECT_EQ(frame.wanted_level, wanted);
  EXPECT_EQ(client.loader().finest_loaded(), wanted);
  EXPECT_EQ(client.arrivals().size(), levels - wanted);
  EXPECT_LE(frame.report.faces, options.budget);
  const MultilevelMesh on_grid = snapped_multilevel(model.mesh, kDefaultPositionBits);
  MultilevelLod full(on_grid);
  full.set_level(wanted);
  const auto got = client.lod().indices(), expected = full.indices();
  EXPECT_TRUE(std::equal(got.begin(), got.end(), expected.begin(), expected.end()));
  ASSERT_EQ(client.lod().vertex_count(), full.vertex_count());
  const auto p = client.lod().positions(), q = full.positions();
  EXPECT_TRUE(std::equal(p.begin(), p.end(), q.begin(), q.end()));
}

client::MultilevelOptions with_geomorphs(uint32_t frames) {
  client::MultilevelOptions options;
  options.morph_frames = frames;
  return options;
}

// The screen-size rule asks for finer levels as the camera closes in; each switch is one geomorph that
// ends on the wanted level after morph_frames frames at the same camera.
TEST(MultilevelHttp, CloserCamerasWantFinerLevels) {
  Server server;
  const client::MultilevelOptions options = with_geomorphs(4);
  client::MultilevelClient client(server.url(), options);
  client.open("ball");
  uint32_t previous = ~0u;
  for (float distance : {400.0f, 40.0f, 8.0f, 3.0f, 1.5f}) {
    Camera c;
    c.eye[2] = distance;
    client::MultilevelFrame frame = client.frame(c);
    EXPECT_LE(frame.wanted_level, previous) << "distance " << distance;
    for (uint32_t i = 1; i < options.morph_frames; ++i) frame = client.frame(c);
    EXPECT_EQ(frame.level, float(frame.wanted_level)) << "distance " << distance;
    EXPECT_FALSE(client.in_motion()) << "distance " << distance;
    previous = frame.wanted_level;
  }
  EXPECT_LT(previous, sphere_model().mesh.level_count() - 1);
}

// A switch from the coarsest LOD to the finest is one geomorph (gueziec et al.: the two LODs blended),
// not one per level in between: the level shown moves the same part of the way each frame, the client is
// in motion until it shows the wanted level (an integral level on the way is still motion), and
// morph_frames frames reach it. A switch back to where it came from reverses it.
TEST(MultilevelHttp, AFarSwitchIsOneGeomorph) {
  Server server;
  const client::MultilevelOptions options = with_geomorphs(8);
  client::MultilevelClient client(server.url(), options);
  client.open("ball");
  const float top = float(sphere_model().mesh.level_count() - 1);
  Camera far = far_camera(), near;
  near.eye[2] = 1.2f;
  EXPECT_EQ(client.frame(far).level, top);
  EXPECT_FALSE(client.in_motion());
  const uint32_t wanted = client.wanted_level(near);
  ASSERT_LT(float(wanted) + 2, top) << "the switch crosses several levels";
  float shown = top;
  for (uint32_t i = 1; i <= options.morph_frames; ++i) {
    const client::MultilevelFrame frame = client.frame(near);
    const float expected = top + (float(wanted) - top) * float(i) / float(options.morph_frames);
    EXPECT_NEAR(frame.level, expected, 1e-4f) << "frame " << i;
    EXPECT_LT(frame.level, shown) << "frame " << i;
    EXPECT_EQ(client.in_motion(), i < options.morph_frames) << "frame " << i << ", level " << frame.level;
    shown = frame.level;
  }
  EXPECT_EQ(shown, float(wanted));
  // Halfway back to the coarsest, then forward again: the same geomorph, reversed twice.
  for (uint32_t i = 0; i < options.morph_frames / 2; ++i) client.frame(far);
  EXPECT_NEAR(client.lod().level(), (top + float(wanted)) / 2, 1e-4f);
  EXPECT_TRUE(client.in_motion());
  for (uint32_t i = 0; i < options.morph_frames / 2; ++i) client.frame(near);
  EXPECT_EQ(client.lod().level(), float(wanted));
  EXPECT_FALSE(client.in_motion());
}

TEST(MultilevelHttp, ResourcesAreCacheableAndHostileUrlsGet4xx) {
  const MultilevelModel& model = sphere_model();
  Server server;
  test::HttpTestClient http(server.http.port());
  const test::HttpReply head = http.get(ball() + "/head");
  ASSERT_EQ(head.status, 200);
  EXPECT_EQ(head.body.size(), 32u);
  const test::HttpReply level = http.get(ball() + "/levels/0");
  ASSERT_EQ(level.status, 200);
  EXPECT_EQ(level.header("cache-control"), "max-age=31536000, immutable");
  const std::string etag = level.header("etag");
  ASSERT_FALSE(etag.empty());
  EXPECT_EQ(http.get(ball() + "/levels/0").body, level.body) << "the same bytes for the same URL";
  EXPECT_EQ(http.get(ball() + "/levels/0", {{"If-None-Match", etag}}).status, 304);
  EXPECT_NE(http.get(ball() + "/levels/1").header("etag"), etag);
  const std::string last = std::to_string(model.mesh.level_count());
  EXPECT_EQ(http.get(ball() + "/levels/" + last).status, 404);
  EXPECT_EQ(http.get(ball() + "/levels/01").status, 400);
  EXPECT_EQ(http.get(ball() + "/levels/-1").status, 400);
  EXPECT_EQ(http.get(ball() + "/levels/99999999999999999999999").status, 400);
  EXPECT_EQ(http.get(ball() + "/levels").status, 404);
  // The compressed form: its own resources, as cacheable, smaller, with ETags of their own.
  const test::HttpReply zhead = http.get(ball() + "/compressed/head");
  ASSERT_EQ(zhead.status, 200);
  EXPECT_EQ(zhead.body.size(), 80u);  // 64, and the texture coordinates' grid box
  const test::HttpReply zlevel = http.get(ball() + "/compressed/levels/0");
  ASSERT_EQ(zlevel.status, 200);
  EXPECT_LT(zlevel.body.size(), level.body.size());
  EXPECT_EQ(zlevel.header("cache-control"), "max-age=31536000, immutable");
  const std::string zetag = zlevel.header("etag");
  EXPECT_FALSE(zetag.empty());
  EXPECT_NE(zetag, etag);
  EXPECT_EQ(http.get(ball() + "/compressed/levels/0", {{"If-None-Match", zetag}}).status, 304);
  EXPECT_EQ(http.get(ball() + "/compressed/levels/" + last).status, 404);
  EXPECT_EQ(http.get(ball() + "/compressed/levels/01").status, 400);
  EXPECT_EQ(http.get(ball() + "/compressed").status, 404);
  EXPECT_EQ(http.get(ball() + "/compressed/compressed/head").status, 404);
  EXPECT_EQ(http.get(ball() + "/base").status, 404);
  EXPECT_EQ(http.get("/models/nosuch/head").status, 404);
  EXPECT_EQ(http.get("/models/ball/head").status, 404);  // no version
  EXPECT_EQ(http.post(ball() + "/head", {1, 2}).status, 405);
  const test::HttpReply catalogue = http.get("/models");
  EXPECT_NE(catalogue.text().find("\"kind\":\"multilevel\""), std::string::npos) << catalogue.text();
  EXPECT_NE(catalogue.text().find("\"texcoords\":true"), std::string::npos) << catalogue.text();

  client::MultilevelClient client(server.url());
  EXPECT_THROW(client.open("nosuch"), Error);
}

}  // namespace
}  // namespace pms
