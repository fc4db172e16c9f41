// The receiver-driven Viewer free-running over real loopback: a frame returns with its answers still
// outstanding when the server answers late (a holding proxy), a view that moves on drops the ids it queued
// for the last one, and after settling the mesh is local refinement's at the last camera and lock-step's
// along the same path.
#include <gtest/gtest.h>
#include <string>
#include <vector>

#include "client/receiver_viewer.h"
#include "client/viewer.h"
#include "holding_proxy.h"
#include "streaming_fixture.h"

namespace pms {
namespace {

using client::Pacing;
using client::ReceiverViewer;
using client::ViewerReport;
using test::faces_by_id;
using test::Fixture;
using test::local_faces;
using test::orbit_path;
using test::vertices_by_id;

const Fixture& terrain() { return test::terrain_fixture(30000, 5); }

std::string http_url(const test::LoopbackHttpServer& server) {
  return "http://127.0.0.1:" + std::to_string(server.port());
}

SelectiveMesh& mesh_of(ReceiverViewer& viewer) { return viewer.client().session().mesh(); }

client::ReceiverOptions with_ids_per_request(uint32_t ids) {
  client::ReceiverOptions options;
  options.ids_per_request = ids;
  return options;
}

// The terrain's server behind a holding proxy, and a free-running viewer through the proxy.
struct Held {
  explicit Held(uint32_t ids_per_request)
      : proxy(server.port()),
        viewer(proxy.http_url(), with_ids_per_request(ids_per_request), Pacing::free_running, "terrain") {}
  // A frame whose answers the server has sent and the proxy holds.
  ViewerReport frame_answered_late(const Camera& camera) {
    proxy.hold();
    const ViewerReport report = viewer.frame(camera);
    EXPECT_TRUE(proxy.wait_held(1)) << "the server answered";
    return report;
  }
  test::LoopbackHttpServer server{terrain().catalogue};
  test::HoldingProxy proxy;
  ReceiverViewer viewer;
};

TEST(ReceiverFree, AFrameReturnsWithItsAnswersHeldAndSettlingEndsOnLocalRefinement) {
  const Fixture& f = terrain();
  Held held(16);
  auto& [server, proxy, viewer] = held;
  const Camera camera = orbit_path(f.hierarchy, 10, 0.3f).back();
  const ViewerReport first = held.frame_answered_late(camera);
  EXPECT_FALSE(first.satisfied);
  EXPECT_EQ(first.received, 0u);
  EXPECT_EQ(first.in_flight, client::HttpOptions{}.in_flight) << "the pipe filled, its answers to come";
  EXPECT_GT(first.up_bytes, 0u);
  const ViewerReport second = viewer.frame(camera);
  EXPECT_EQ(second.received, 0u) << "the answers wait in the proxy: the frame returned without them";
  EXPECT_EQ(second.down_bytes, 0u);
  EXPECT_EQ(second.in_flight, first.in_flight);
  EXPECT_FALSE(second.satisfied);
  proxy.release();
  viewer.settle(camera);
  EXPECT_EQ(faces_by_id(mesh_of(viewer)), local_faces(f.snapped, camera, 1.0f));
  const ViewerReport after = viewer.frame(camera);
  EXPECT_TRUE(after.satisfied);
  EXPECT_EQ(after.in_flight, 0u);
  EXPECT_EQ(after.up_bytes, 0u) << "a settled view asks for nothing more";
}

// The connection closes with GETs written and their answers not yet read (as a server closing a kept-alive
// connection does): the GETs go again on a new connection, without a frame waiting for it.
TEST(ReceiverFree, GetsInFlightWhenTheConnectionClosesAreSentAgain) {
  const Fixture& f = terrain();
  Held held(64);
  auto& [server, proxy, viewer] = held;
  const Camera camera = orbit_path(f.hierarchy, 10, 0.3f).back();
  ASSERT_GT(held.frame_answered_late(camera).in_flight, 0u);
  proxy.drop();
  proxy.release();
  viewer.frame(camera);  // sees the close and connects again, without waiting for it
  viewer.settle(camera);
  EXPECT_EQ(faces_by_id(mesh_of(viewer)), local_faces(f.snapped, camera, 1.0f));
  EXPECT_EQ(viewer.client().counters().connections, 2u);
}

// A viewer closed with GETs on the wire and answers held: nothing waits for them, nothing is left behind.
TEST(ReceiverFree, AViewerClosedWithAnswersOutstandingEndsAtOnce) {
  const Fixture& f = terrain();
  for (int round = 0; round < 2; ++round) {
    Held held(16);
    ASSERT_GT(held.frame_answered_late(orbit_path(f.hierarchy, 10, 0.3f).back()).in_flight, 0u);
  }
}

// Both views' wants are ranked while every answer is held: the second frame's ranking drops the ids queued
// for the first view that it does not want, unsent. The GETs already written are answered and attached
// (HTTP/1.1 cannot take them back), and the settled mesh is the second view's.
TEST(ReceiverFree, AViewThatMovesOnDropsWhatItQueuedForTheLast) {
  const Fixture& f = terrain();
  Held held(8);
  auto& [server, proxy, viewer] = held;
  const Camera near = orbit_path(f.hierarchy, 10, 0.3f).back();
  const Camera across = orbit_path(f.hierarchy, 10, 0.3f + 3.1f).back();
  proxy.hold();
  const ViewerReport first = viewer.frame(near);
  ASSERT_GT(first.details["queued"].get<uint32_t>(), 0u) << "more wanted than the pipe holds";
  const ViewerReport jump = viewer.frame(across);
  EXPECT_GT(jump.details["cancelled"].get<uint32_t>(), 0u) << "ids queued for the near view, dropped unsent";
  EXPECT_EQ(jump.received, 0u);
  proxy.release();
  viewer.settle(across);
  EXPECT_EQ(faces_by_id(mesh_of(viewer)), local_faces(f.snapped, across, 1.0f));
  EXPECT_EQ(viewer.client().totals().cancelled, jump.details["cancelled"].get<uint64_t>());
}

// Along an orbit, free-running frames against lock-step ones on the same server: after settling at the last
// camera both hold local refinement's mesh, with the same values; with prefetch and with blocks too.
TEST(ReceiverFree, SettledAlongAnOrbitItIsLockStepsMesh) {
  const Fixture& f = terrain();
  test::LoopbackHttpServer server(f.catalogue);
  struct Variant {
    client::FetchPolicy fetch;
    bool prefetch;
  };
  for (const Variant variant : {Variant{client::FetchPolicy::lists, false}, Variant{client::FetchPolicy::blocks, false},
                                Variant{client::FetchPolicy::lists, true}}) {
    client::ReceiverOptions options;
    options.ids_per_request = 16;
    options.fetch = variant.fetch;
    options.prefetch = variant.prefetch;
    ReceiverViewer free(http_url(server), options, Pacing::free_running, "terrain");
    ReceiverViewer locked(http_url(server), options, Pacing::lock_step, "terrain");
    const std::vector<Camera> path = orbit_path(f.hierarchy, 20, 0.3f);
    uint64_t requested = 0;
    for (const Camera& camera : path) {
      requested += free.frame(camera).up_bytes > 0;
      EXPECT_TRUE(locked.frame(camera).satisfied);
    }
    EXPECT_GT(requested, 0u);
    free.settle(path.back());
    locked.settle(path.back());
    const std::string name =
        client::fetch_policy_name(variant.fetch) + std::string(variant.prefetch ? "+prefetch" : "");
    EXPECT_EQ(faces_by_id(mesh_of(free)), faces_by_id(mesh_of(locked))) << name;
    EXPECT_EQ(faces_by_id(mesh_of(free)), local_faces(f.snapped, path.back(), 1.0f)) << name;
    EXPECT_EQ(vertices_by_id(mesh_of(free)), vertices_by_id(mesh_of(locked))) << name;
  }
}

}  // namespace
}  // namespace pms
