// The HTTP clients over a transport that is not HttpConnection (in_process_http.h: the server's routes
// called in process, answering when the test says so): a free-running frame returns with its GETs
// outstanding, and settling ends where lock-step does — local refinement for the receiver-driven client,
// the rule's level for the multilevel one. Nothing in the clients knows which transport they run over.
#include <gtest/gtest.h>

#include <memory>
#include <utility>

#include "client/http_transport.h"
#include "client/multilevel_client.h"
#include "client/receiver_client.h"
#include "in_process_http.h"
#include "streaming_fixture.h"

namespace pms {
namespace {

using test::faces_by_id;
using test::Fixture;
using test::InProcessHttp;
using test::local_faces;
using test::orbit_path;

const Fixture& terrain() { return test::terrain_fixture(30000, 5); }

// `Client` over the terrain's routes in process.
template <class Client, class Options>
struct OverInProcess : test::OverInProcess<Client, Options> {
  OverInProcess(const Options& options, bool free_running)
      : test::OverInProcess<Client, Options>(terrain().catalogue, "terrain", options, free_running) {}
};

client::ReceiverOptions receiver_options() {
  client::ReceiverOptions options;
  options.ids_per_request = 16;
  return options;
}

TEST(InProcessHttp, AReceiverFrameReturnsWithItsGetsOutstandingAndSettlesOnLocalRefinement) {
  const Fixture& f = terrain();
  OverInProcess<client::ReceiverClient, client::ReceiverOptions> free(receiver_options(), true);
  const Camera camera = orbit_path(f.hierarchy, 10, 0.3f).back();
  free.http->hold(true);
  const client::ReceiverFrame first = free.client->frame(camera);
  EXPECT_FALSE(first.satisfied);
  EXPECT_EQ(first.answers, 0u);
  EXPECT_EQ(first.in_flight, 4u) << "the pipe filled";
  EXPECT_EQ(free.http->pending(), 4u) << "and not one answered: the frame did not wait";
  const client::ReceiverFrame second = free.client->frame(camera);
  EXPECT_EQ(second.answers, 0u);
  EXPECT_EQ(second.in_flight, first.in_flight);
  free.http->hold(false);
  EXPECT_GT(free.client->frame(camera).answers, 0u) << "released: the next frame attaches them";
  free.client->settle(camera);
  const test::Faces settled = faces_by_id(free.client->session().mesh());
  EXPECT_EQ(settled, local_faces(f.snapped, camera, 1.0f));
  EXPECT_TRUE(free.client->frame(camera).satisfied);
  EXPECT_EQ(free.http->pending(), 0u);

  OverInProcess<client::ReceiverClient, client::ReceiverOptions> locked(receiver_options(), false);
  locked.http->hold(true);  // lock-step answers by waiting: a held transport still serves it
  EXPECT_TRUE(locked.client->frame(camera).satisfied);
  EXPECT_EQ(faces_by_id(locked.client->session().mesh()), settled);
}

TEST(InProcessHttp, AMultilevelFrameReturnsWithItsLevelsOutstandingAndSettlesOnLockStepsLevel) {
  const Fixture& f = terrain();
  OverInProcess<client::MultilevelClient, client::MultilevelOptions> free({}, true);
  const Camera camera = orbit_path(f.hierarchy, 10, 0.3f).back();
  const uint32_t wanted = free.client->wanted_level(camera);
  ASSERT_LT(wanted, free.client->loader().finest_loaded()) << "the camera wants finer levels than open's";
  free.http->hold(true);
  const client::MultilevelFrame first = free.client->frame(camera);
  EXPECT_GT(first.in_flight, 0u);
  EXPECT_EQ(free.http->pending(), first.in_flight) << "not one answered: the frame did not wait";
  EXPECT_EQ(free.client->frame(camera).report.vsplits, 0u) << "no level while held";
  free.http->hold(false);
  free.client->settle(camera);
  OverInProcess<client::MultilevelClient, client::MultilevelOptions> locked({}, false);
  locked.client->frame(camera);
  locked.client->settle(camera);
  EXPECT_EQ(free.client->loader().finest_loaded(), wanted);
  EXPECT_EQ(free.client->lod().level(), locked.client->lod().level());
  const Mesh got = free.client->current_mesh(), want = locked.client->current_mesh();
  EXPECT_EQ(got.positions, want.positions);
  EXPECT_EQ(got.indices, want.indices);
  EXPECT_GT(got.face_count(), 0u);
}

}  // namespace
}  // namespace pms
