// The multilevel Viewer free-running over real loopback, on the terrain's derived levels: the coarsest
// level comes in open's round trip (GET .../levels/coarsest beside the entry and the head), a frame returns
// with the finer levels it asked for still outstanding when the server answers late (a holding proxy), and
// after settling the mesh is lock-step's at the last camera.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "client/http_connection.h"
#include "client/multilevel_viewer.h"
#include "client/viewer.h"
#include "holding_proxy.h"
#include "streaming_fixture.h"

namespace pms {
namespace {

using client::MultilevelViewer;
using client::Pacing;
using client::ViewerReport;
using test::Fixture;
using test::orbit_path;

const Fixture& terrain() { return test::terrain_fixture(30000, 5); }

std::string http_url(const test::LoopbackHttpServer& server) {
  return "http://127.0.0.1:" + std::to_string(server.port());
}

void expect_same_mesh(const Mesh& got, const Mesh& want) {
  EXPECT_EQ(got.positions, want.positions);
  EXPECT_EQ(got.normals, want.normals);
  EXPECT_EQ(got.colors, want.colors);
  EXPECT_EQ(got.indices, want.indices);
  EXPECT_GT(got.face_count(), 0u);
}

TEST(MultilevelFree, TheCoarsestLevelNamedByItsNameIsTheLastLevel) {
  test::LoopbackHttpServer server(terrain().catalogue);
  client::HttpConnection http(server.url());
  const std::string at = test::model_url(*terrain().catalogue, "terrain");
  for (const std::string& prefix : {at + "/", at + "/compressed/"}) {
    const client::HttpAnswer entry = http.get(at + "/multilevel");
    ASSERT_EQ(entry.status, 200);
    const uint32_t levels = nlohmann::json::parse(entry.body.begin(), entry.body.end())["levels"].get<uint32_t>();
    const client::HttpAnswer coarsest = http.get(prefix + "levels/coarsest");
    const client::HttpAnswer last = http.get(prefix + "levels/" + std::to_string(levels - 1));
    ASSERT_EQ(coarsest.status, 200) << prefix;
    EXPECT_EQ(coarsest.body, last.body) << prefix;
    EXPECT_EQ(http.get(prefix + "levels/finest").status, 400) << prefix << ": no other name";
  }
}

TEST(MultilevelFree, AFrameReturnsWithItsLevelsHeldAndSettlingEndsOnLockStepsMesh) {
  const Fixture& f = terrain();
  test::LoopbackHttpServer server(f.catalogue);
  test::HoldingProxy proxy(server.port());
  MultilevelViewer viewer(proxy.http_url(), {}, Pacing::free_running, "terrain");
  ASSERT_EQ(viewer.client().arrivals().size(), 1u) << "the coarsest level came in open's round trip";
  const uint32_t levels = viewer.client().loader().level_count();
  const Camera camera = orbit_path(f.hierarchy, 10, 0.3f).back();
  ASSERT_LT(viewer.client().wanted_level(camera), levels - 1) << "the camera wants finer levels";
  proxy.hold();
  const ViewerReport first = viewer.frame(camera);
  EXPECT_GT(first.faces, 0u) << "the coarsest level's picture, at once";
  EXPECT_EQ(first.received, 0u);
  EXPECT_GT(first.in_flight, 0u);
  EXPECT_FALSE(first.satisfied);
  ASSERT_TRUE(proxy.wait_held(1)) << "the server answered";
  const ViewerReport second = viewer.frame(camera);
  EXPECT_EQ(second.received, 0u) << "the levels wait in the proxy: the frame returned without them";
  EXPECT_EQ(second.in_flight, first.in_flight);
  EXPECT_EQ(second.details["levels_loaded"].get<uint32_t>(), 1u);
  proxy.release();
  viewer.settle(camera);
  MultilevelViewer locked(http_url(server), {}, Pacing::lock_step, "terrain");
  locked.frame(camera);
  locked.settle(camera);
  expect_same_mesh(viewer.mesh(), locked.mesh());
  const ViewerReport after = viewer.frame(camera);
  EXPECT_TRUE(after.satisfied);
  EXPECT_EQ(after.in_flight, 0u);
}

// Along an orbit, free-running frames against lock-step ones: after settling at the last camera both show
// the same LOD, with geomorphs and without.
TEST(MultilevelFree, SettledAlongAnOrbitItIsLockStepsMesh) {
  const Fixture& f = terrain();
  test::LoopbackHttpServer server(f.catalogue);
  for (const uint32_t morph_frames : {0u, 4u}) {
    client::MultilevelOptions options;
    options.morph_frames = morph_frames;
    MultilevelViewer free(http_url(server), options, Pacing::free_running, "terrain");
    MultilevelViewer locked(http_url(server), options, Pacing::lock_step, "terrain");
    const std::vector<Camera> path = orbit_path(f.hierarchy, 20, 0.3f);
    for (const Camera& camera : path) {
      free.frame(camera);
      locked.frame(camera);
    }
    free.settle(path.back());
    locked.settle(path.back());
    expect_same_mesh(free.mesh(), locked.mesh());
    EXPECT_LT(free.client().loader().finest_loaded(), free.client().loader().level_count() - 1);
  }
}

}  // namespace
}  // namespace pms
