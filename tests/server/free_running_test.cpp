// The session modes free-running (sender, sender-plain, vi, dag; client/free_running_session.h) over real
// loopback TCP: a frame never waits for the network (answers held back by the test stay outstanding when
// it returns), and after settling the mesh is what lock-step gives at the last camera; a lost connection
// is resumed by later frames, none of them sleeping, and the session ends where an unbroken one does; the DAG
// client's FREE/BUDGET management counts its requests in flight against the budget.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "client/link.h"
#include "client/session_viewer.h"
#include "client/streaming_client.h"
#include "client/transport.h"
#include "protocol/client_messages.h"
#include "protocol/framing.h"
#include "protocol/message_types.h"
#include "protocol/stream_mode.h"
#include "server/limits.h"
#include "streaming_fixture.h"

namespace pms {
namespace {

using protocol::StreamMode;
using test::faces_by_id;
using test::local_faces;
using test::orbit_path;
using Server = test::LoopbackTcpServer;
using Clock = std::chrono::steady_clock;

constexpr float kTolerance = 1.0f;

const test::Fixture& terrain() { return test::terrain_fixture(30000, 7); }

client::ClientOptions options_for(StreamMode mode) {
  client::ClientOptions options{kTolerance};
  options.mode = mode;
  // The DAG mode's priority traversal converges to the view's mesh (zheng-chan §5), so its settled cut is
  // one lock-step reaches too.
  options.dag.max_ops = 300;
  return options;
}

// A Link whose answers the test holds back, as a server that answers late: while held, receive() hands
// nothing over, and one that would wait returns at once and is counted.
class HeldLink : public client::Transport {
 public:
  explicit HeldLink(uint16_t port) : link_("127.0.0.1", port) {}
  void send(const std::vector<uint8_t>& frame) override { link_.send(frame); }
  std::optional<protocol::Frame> receive(std::chrono::milliseconds timeout) override {
    if (!held) return link_.receive(timeout);
    if (timeout.count() > 0) ++waits;
    return std::nullopt;
  }
  client::LinkCounters counters() const override { return link_.counters(); }

  bool held = false;
  uint32_t waits = 0;  // receives that would have waited while held

 private:
  client::Link link_;
};

// Lock-step along `path`, then settled; the DAG mode framed at the last camera until its cut stops moving,
// which is where free-running settles (the traversal's fixed point).
client::StreamingClient& lock_step(client::StreamingClient& client, const std::vector<Camera>& path, StreamMode mode) {
  for (const Camera& camera : path) client.frame(camera);
  client.settle(path.back());
  for (int round = 0; mode == StreamMode::dag && round < 64; ++round) {
    const uint64_t faces = client.session().mesh().face_count();
    if (client.frame(path.back()).vsplits == 0 && client.session().mesh().face_count() == faces) break;
  }
  return client;
}

void expect_settled_equals_lock_step(StreamMode mode) {
  SCOPED_TRACE(protocol::mode_name(mode));
  const test::Fixture& f = terrain();
  Server server(f.catalogue);
  const std::vector<Camera> path = orbit_path(f.hierarchy, 12, 0.3f);
  auto held = std::make_unique<HeldLink>(server.port());
  HeldLink& link = *held;
  client::StreamingClient client(std::move(held), options_for(mode));
  client.open("terrain");
  const uint64_t base_faces = client.session().mesh().face_count();

  // The whole flight with every answer held back: each frame returns, the first one's request outstanding.
  link.held = true;
  for (size_t i = 0; i < path.size(); ++i) {
    const client::FrameReport r = client.frame_free_running(path[i]);
    if (i == 0) {
      EXPECT_TRUE(r.requested) << "the first view lacks everything";
      EXPECT_EQ(r.in_flight, 1u);
    }
    EXPECT_GE(r.in_flight, 1u) << "frame " << i << ": nothing has been answered";
    EXPECT_FALSE(r.satisfied) << "frame " << i;
    EXPECT_EQ(r.vsplits, 0u) << "frame " << i;  // the bytes may be in: the Link counts them as they arrive
  }
  EXPECT_EQ(link.waits, 0u) << "a free-running frame never waits for an answer";
  if (mode != StreamMode::sender_driven) {
    EXPECT_EQ(client.session().mesh().face_count(), base_faces) << "nothing applied before it arrived";
  }

  link.held = false;
  client.settle_free_running(path.back());
  const client::FrameReport after = client.frame_free_running(path.back());
  EXPECT_TRUE(after.satisfied);
  EXPECT_EQ(after.in_flight, 0u);
  EXPECT_FALSE(after.requested) << "a settled view asks nothing more";

  // Settled is lock-step's fixed point at the last camera: a lock-step frame there changes nothing.
  const test::Faces settled = faces_by_id(client.session().mesh());
  const uint64_t splits = client.session().splits_received();
  const client::FrameReport again = client.frame(path.back());
  EXPECT_EQ(again.vsplits, 0u);
  EXPECT_EQ(faces_by_id(client.session().mesh()), settled);
  if (mode == StreamMode::sender_driven) {
    EXPECT_EQ(again.up_bytes + again.down_bytes, 0u) << "the sender asks only for what it lacks";
  }

  // A lock-step flight of the same path. The modes whose mesh depends on the view alone (sender: local
  // refinement; the DAG's priority traversal at its fixed point) end on the same mesh; those that never
  // coarsen (vi, sender-plain) hold what the views the server got to asked for, a part of what every
  // view of the path asked for.
  client::StreamingClient reference("127.0.0.1", server.port(), options_for(mode), "terrain");
  const test::Faces expected = faces_by_id(lock_step(reference, path, mode).session().mesh());
  if (mode == StreamMode::sender_driven || mode == StreamMode::dag) {
    EXPECT_EQ(settled, expected) << "the settled mesh is lock-step's";
    EXPECT_EQ(settled, local_faces(f.snapped, path.back(), kTolerance));
  } else {
    EXPECT_LE(splits, reference.session().splits_received());
  }
}

TEST(FreeRunning, SenderNeverWaitsAndSettlesToLocalRefinement) {
  expect_settled_equals_lock_step(StreamMode::sender_driven);
}
TEST(FreeRunning, SenderPlainNeverWaitsAndSettlesWhereLockStepAsksNothing) {
  expect_settled_equals_lock_step(StreamMode::sender_plain);
}
TEST(FreeRunning, ViewIndependentNeverWaitsAndSettlesWhereLockStepAsksNothing) {
  expect_settled_equals_lock_step(StreamMode::view_independent);
}
TEST(FreeRunning, DagNeverWaitsAndSettlesToLockStepsFixedPoint) { expect_settled_equals_lock_step(StreamMode::dag); }

// A Link that reads back the DAG_VIEWs it sends: their FREE or BUDGET mode.
class DagViewsSeen : public client::Transport {
 public:
  explicit DagViewsSeen(uint16_t port) : link_("127.0.0.1", port) {}
  void send(const std::vector<uint8_t>& frame) override {
    reader_.feed(frame);
    for (protocol::Frame f; reader_.next(f);)
      if (f.type == protocol::MessageType::dag_view)
        ++(protocol::decode_dag_view(f.payload).management == DagMode::free ? free : budget);
    link_.send(frame);
  }
  std::optional<protocol::Frame> receive(std::chrono::milliseconds timeout) override { return link_.receive(timeout); }
  client::LinkCounters counters() const override { return link_.counters(); }

  uint32_t free = 0, budget = 0;

 private:
  client::Link link_;
  protocol::FrameReader reader_;
};

// zheng-chan's management free-running (--management auto --fps): the requests in flight count against
// the budget, so FREE requests never take the mesh past it however many are answered at once.
TEST(FreeRunning, DagManagementAutoKeepsTheBudgetWithRequestsInFlight) {
  const test::Fixture& f = terrain();
  Server server(f.catalogue);
  const std::vector<Camera> path = orbit_path(f.hierarchy, 24, 0.3f);
  client::ClientOptions options = options_for(StreamMode::dag);
  options.dag.max_ops = 100;
  options.dag.management = DagMode::budget;
  options.dag.budget = 1800;
  options.dag_management.automatic = true;
  auto seen = std::make_unique<DagViewsSeen>(server.port());
  DagViewsSeen& link = *seen;
  client::StreamingClient client(std::move(seen), options);
  client.open("terrain");
  uint64_t most = 0;
  for (const Camera& camera : path) {
    client.frame_free_running(camera);
    most = std::max<uint64_t>(most, client.session().mesh().face_count());
  }
  client.settle_free_running(path.back());
  most = std::max<uint64_t>(most, client.session().mesh().face_count());
  EXPECT_LE(most, options.dag.budget);
  EXPECT_GT(most, options.dag.budget * 3 / 4) << "the budget is what held the mesh back";
  EXPECT_GT(link.free, 0u);
  EXPECT_GT(link.budget, 1u) << "only the first request asked in BUDGET mode";
}

// A lost connection, free-running: frames go on with the mesh held and nothing in flight, each makes at
// most one reconnect attempt and only once the backoff's delay has passed (no frame sleeps it away), and
// the resumed session ends where an unbroken one does.
TEST(FreeRunning, ALostConnectionIsResumedByLaterFramesThatNeverSleep) {
  const test::Fixture& f = terrain();
  auto server = std::make_unique<Server>(f.catalogue);
  const uint16_t port = server->port();
  const std::vector<Camera> path = orbit_path(f.hierarchy, 10, 1.1f);
  const size_t half = path.size() / 2;
  client::ClientOptions options{kTolerance};
  options.reconnect_attempts = 8;
  options.reconnect_delay = std::chrono::milliseconds(200);
  std::vector<uint32_t> attempts;
  std::vector<std::string> reasons;
  options.on_reconnect = [&](const std::string& reason, uint32_t attempt) {
    reasons.push_back(reason);
    attempts.push_back(attempt);
  };
  client::SessionViewer viewer("127.0.0.1:" + std::to_string(port), options, client::Pacing::free_running, "terrain");
  for (size_t i = 0; i < half; ++i) viewer.frame(path[i]);
  viewer.settle(path[half - 1]);

  server.reset();
  size_t frames_between = 0;  // frames after the loss that made no attempt
  const Clock::time_point deadline = Clock::now() + std::chrono::seconds(30);
  while (attempts.size() < 2 && Clock::now() < deadline) {
    const size_t before = attempts.size();
    const client::ViewerReport r = viewer.frame(path[half]);
    ASSERT_LE(attempts.size(), before + 1) << "one attempt a frame at most";
    if (attempts.empty()) continue;
    frames_between += attempts.size() == before;
    EXPECT_EQ(r.in_flight, 0u) << "what was in flight went with the connection";
    EXPECT_FALSE(r.satisfied);
  }
  ASSERT_EQ(attempts, (std::vector<uint32_t>{1, 2}));
  EXPECT_GT(frames_between, 0u) << "the backoff passes over frames, not inside one";
  EXPECT_TRUE(reasons[0].find("server: connection lost") != std::string::npos) << reasons[0];
  EXPECT_TRUE(reasons[1].find("cannot connect") != std::string::npos) << reasons[1];

  server = std::make_unique<Server>(f.catalogue, server::ServerLimits{}, port);
  for (size_t i = half; i < path.size(); ++i) viewer.frame(path[i]);
  viewer.settle(path.back());
  EXPECT_GE(attempts.size(), 3u);
  EXPECT_EQ(faces_by_id(viewer.client().session().mesh()), local_faces(f.snapped, path.back(), kTolerance));
}

}  // namespace
}  // namespace pms
