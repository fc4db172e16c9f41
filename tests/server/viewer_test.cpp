// The Viewer over every mode, on real loopback servers: opened by name, flown along a path in both pacings,
// settled. Settled free-running ends where lock-step does (the mode's promise: sender and receiver equal
// local refinement, dag the server's fixed point, multilevel the rule's level); vi and sender-plain, which
// never coarsen, end with nothing more wanted by the last view. The buffers draw the mesh the viewer shows.
#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <vector>

#include "client/viewer.h"
#include "io/mesh.h"
#include "streaming_fixture.h"

namespace pms::test {
namespace {

const Fixture& terrain() { return terrain_fixture(20000, 3); }

struct Servers {
  LoopbackTcpServer tcp{terrain().catalogue};
  LoopbackHttpServer http{terrain().catalogue};
  std::string address(const std::string& mode) const {
    if (mode == "receiver" || mode == "multilevel") return "http://127.0.0.1:" + std::to_string(http.port());
    return "127.0.0.1:" + std::to_string(tcp.port());
  }
};

std::unique_ptr<client::Viewer> open(const Servers& servers, const std::string& mode, client::Pacing pacing) {
  client::ViewerOptions options;
  options.mode = mode;
  options.server = servers.address(mode);
  options.pacing = pacing;
  return client::open_viewer(options, "terrain");
}

std::vector<PositionedTriangle> triangles(const Mesh& mesh) { return positioned_triangles(mesh.positions, mesh.indices); }

std::vector<PositionedTriangle> fly_and_settle(client::Viewer& viewer, const std::vector<Camera>& path) {
  for (const Camera& camera : path) viewer.frame(camera);
  viewer.settle(path.back());
  return triangles(viewer.mesh());
}

TEST(Viewer, EveryModeSettlesWhereLockStepDoes) {
  Servers servers;
  const std::vector<Camera> path = orbit_path(terrain().hierarchy, 24, 0.4f);
  for (const std::string mode : {"sender", "sender-plain", "vi", "dag", "receiver", "multilevel"}) {
    SCOPED_TRACE(mode);
    const auto lock_step = open(servers, mode, client::Pacing::lock_step);
    const auto free_running = open(servers, mode, client::Pacing::free_running);
    const std::vector<PositionedTriangle> expected = fly_and_settle(*lock_step, path);
    const std::vector<PositionedTriangle> settled = fly_and_settle(*free_running, path);
    if (mode == "vi" || mode == "sender-plain") {
      // Views overtaken on their way asked for nothing: the last one wants nothing more.
      const uint64_t before = free_running->received_total();
      free_running->settle(path.back());
      EXPECT_EQ(free_running->received_total(), before);
    } else {
      EXPECT_EQ(settled, expected);
    }
    EXPECT_GT(free_running->received_total(), 0u);
  }
}

TEST(Viewer, BuffersDrawTheMeshShown) {
  Servers servers;
  const std::vector<Camera> path = orbit_path(terrain().hierarchy, 12, 0.1f);
  for (const std::string mode : {"sender", "receiver", "multilevel", "dag"}) {
    SCOPED_TRACE(mode);
    const auto viewer = open(servers, mode, client::Pacing::free_running);
    for (const Camera& camera : path) {
      viewer->frame(camera);
      const client::MeshBuffers& buffers = viewer->buffers();
      EXPECT_EQ(positioned_triangles(buffers.positions, buffers.indices), triangles(viewer->mesh()));
    }
  }
}

TEST(Viewer, AnUnknownModeIsAnErrorNamingTheOption) {
  client::ViewerOptions options;
  options.mode = "telepathy";
  options.server = "127.0.0.1:1";
  try {
    client::open_viewer(options, "terrain");
    FAIL() << "an unknown mode was taken";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("--mode"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("multilevel"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace pms::test
