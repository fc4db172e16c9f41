// What the receiver-driven client does beyond the view's wants (cheng-ooi §4.2): it ranks the front again
// on its refresh period while the camera holds still, not on every free-running frame, and with a byte
// budget it keeps fetching the model's remaining splits when idle, largest error first, each once, without
// changing the mesh a view makes. Over the server's routes in process (in_process_http.h), so the test
// decides when answers arrive.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <limits>
#include <string>
#include <thread>

#include "client/receiver_client.h"
#include "in_process_http.h"
#include "spm/refine_info.h"
#include "streaming_fixture.h"

namespace pms {
namespace {

using test::faces_by_id;
using test::Fixture;
using test::local_faces;
using test::orbit_path;
using Free = test::OverInProcess<client::ReceiverClient, client::ReceiverOptions>;

const Fixture& terrain() { return test::terrain_fixture(30000, 5); }

client::ReceiverOptions options(uint32_t rerank_ms, uint64_t background_bytes = 0,
                                client::FetchPolicy fetch = client::FetchPolicy::lists) {
  client::ReceiverOptions o;
  o.ids_per_request = 16;
  o.rerank_ms = rerank_ms;
  o.background_bytes = background_bytes;
  o.fetch = fetch;
  return o;
}

// Every split the client holds came once: the splits received are the hierarchy's split nodes.
uint64_t splits_held(client::ReceiverClient& client) {
  const VertexHierarchy& hierarchy = client.session().hierarchy();
  return (hierarchy.size() - hierarchy.root_count()) / 2;
}

TEST(ReceiverIdle, AStillCameraIsRankedOnTheRefreshPeriodNotEveryFrame) {
  const Fixture& f = terrain();
  const Camera camera = orbit_path(f.hierarchy, 10, 0.3f).back();
  const Camera moved = orbit_path(f.hierarchy, 10, 0.35f).back();

  Free slow(f.catalogue, "terrain", options(60'000), true);
  slow.http->hold(true);
  const client::ReceiverFrame first = slow.client->frame(camera);
  EXPECT_EQ(first.rankings, 1u);
  ASSERT_GT(first.queued, 0u) << "the view wants more than the pipe holds";
  for (int n = 0; n < 5; ++n) {
    const client::ReceiverFrame still = slow.client->frame(camera);
    EXPECT_EQ(still.rankings, 0u) << "the same camera, nothing arrived, ranked lately";
    EXPECT_FALSE(still.satisfied);
    EXPECT_EQ(still.queued, first.queued);
  }
  EXPECT_EQ(slow.client->frame(moved).rankings, 1u) << "a moved camera is ranked at once";
  slow.http->hold(false);
  slow.client->settle(camera);
  EXPECT_EQ(faces_by_id(slow.client->session().mesh()), local_faces(f.snapped, camera, 1.0f));

  Free due(f.catalogue, "terrain", options(20), true);
  due.http->hold(true);
  due.client->frame(camera);
  EXPECT_EQ(due.client->frame(camera).rankings, 0u);
  std::this_thread::sleep_for(std::chrono::milliseconds(30));
  EXPECT_EQ(due.client->frame(camera).rankings, 1u) << "the refresh period is over: ranked with the camera still";

  Free every(f.catalogue, "terrain", options(0), true);
  every.http->hold(true);
  for (int n = 0; n < 3; ++n) EXPECT_EQ(every.client->frame(camera).rankings, 1u) << "0: every frame";
}

// With an unbounded budget the idle fetch brings every split some view may ask for, each once, and the
// mesh stays what the view makes; the view's own GETs always go first.
TEST(ReceiverIdle, TheIdleFetchFillsTheModelInOnceAndChangesNoMesh) {
  const Fixture& f = terrain();
  const Camera camera = orbit_path(f.hierarchy, 10, 0.3f).back();
  for (const client::FetchPolicy fetch : {client::FetchPolicy::lists, client::FetchPolicy::blocks}) {
    SCOPED_TRACE(client::fetch_policy_name(fetch));
    Free idle(f.catalogue, "terrain", options(1000, std::numeric_limits<uint64_t>::max(), fetch), true);
    client::ReceiverClient& client = *idle.client;
    uint32_t frames = 0;
    bool saw_unsatisfied = false;
    for (; frames < 20'000; ++frames) {
      const client::ReceiverFrame r = client.frame(camera);
      if (!r.satisfied) {
        saw_unsatisfied = true;
        EXPECT_EQ(r.background, 0u) << "frame " << r.report.frame << ": the view wants more, nothing idle goes";
      }
      if (r.satisfied && r.background == 0 && r.in_flight == 0) break;
    }
    EXPECT_TRUE(saw_unsatisfied);
    EXPECT_LT(frames, 20'000u);
    EXPECT_GT(client.totals().background_ids, 0u);
    const VertexHierarchy& hierarchy = client.session().hierarchy();
    uint64_t lacked = 0;
    for (uint32_t slot = 0; slot < hierarchy.size(); ++slot)
      lacked += hierarchy.is_leaf(slot) && !never_refines(hierarchy.refine(slot));
    EXPECT_EQ(lacked, 0u) << "leaves held whose splits a view may still ask for";
    EXPECT_EQ(client.session().splits_received(), splits_held(client)) << "a split arrived twice";
    client.settle(camera);
    EXPECT_EQ(faces_by_id(client.session().mesh()), local_faces(f.snapped, camera, 1.0f));
  }
}

TEST(ReceiverIdle, TheIdleFetchStopsAtItsBudgetAndLockStepHasNone) {
  const Fixture& f = terrain();
  const Camera camera = orbit_path(f.hierarchy, 10, 0.3f).back();
  constexpr uint64_t kBudget = 40'000;
  Free idle(f.catalogue, "terrain", options(1000, kBudget), true);
  for (int n = 0; n < 2000; ++n) idle.client->frame(camera);
  const client::ReceiverTotals& totals = idle.client->totals();
  EXPECT_GE(totals.background_bytes, kBudget);
  EXPECT_LT(totals.background_bytes, 2 * kBudget) << "overrun by the GETs in flight at most";
  EXPECT_EQ(idle.client->frame(camera).background, 0u) << "spent: nothing more goes";

  Free locked(f.catalogue, "terrain", options(1000, kBudget), false);
  for (int n = 0; n < 5; ++n) locked.client->frame(camera);
  EXPECT_EQ(locked.client->totals().background_ids, 0u) << "a lock-step frame ends when its view is satisfied";
}

}  // namespace
}  // namespace pms
