// The browser's viewers (client/message_session_viewer.h, the receiver and multilevel viewers over
// client/external_http_transport.h) driven natively against real loopback servers by a pump that moves
// bytes as the page's JS does: TCP frames between a Link and the viewer (one frame = one WebSocket
// message), HTTP answers from an HttpConnection handed over by id. Each frame returns with answers held
// back (it never waits); settled, each ends on the mesh the lock-step native Viewer gets at the same
// camera; a session lost and resumed on a new connection ends where an unbroken one does.
#include <gtest/gtest.h>

#include <chrono>
#include <deque>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "client/external_http_transport.h"
#include "client/face_id_importance.h"
#include "client/http_connection.h"
#include "client/link.h"
#include "client/message_session_viewer.h"
#include "client/multilevel_viewer.h"
#include "client/receiver_viewer.h"
#include "client/session_viewer.h"
#include "protocol/stream_mode.h"
#include "streaming_fixture.h"

namespace pms {
namespace {

using protocol::StreamMode;
using test::faces_by_id;
using test::local_faces;
using test::orbit_path;
using Clock = std::chrono::steady_clock;

constexpr float kTolerance = 1.0f;
// Pump rounds before a test gives up on settling: far more than a flight needs; each waits for bytes
// under a short timeout rather than sleeping.
constexpr int kMaxRounds = 20000;

const test::Fixture& terrain() { return test::terrain_fixture(30000, 7); }

std::vector<uint8_t> wire_bytes(const protocol::Frame& frame) {
  const uint32_t size = uint32_t(frame.payload.size());
  std::vector<uint8_t> out = {uint8_t(size), uint8_t(size >> 8), uint8_t(size >> 16), uint8_t(size >> 24),
                              uint8_t(frame.type)};
  out.insert(out.end(), frame.payload.begin(), frame.payload.end());
  return out;
}

// The page's WebSocket for a session viewer: frames out as they are queued, frames in one at a time.
struct SocketPump {
  SocketPump(client::MessageSessionViewer& viewer, uint16_t port)
      : viewer(viewer), link(std::make_unique<client::Link>("127.0.0.1", port)) {
    viewer.connected();
  }
  void send() {
    for (const std::vector<uint8_t>& frame : viewer.take_outgoing()) link->send(frame);
  }
  // Hands over what has arrived, waiting up to `timeout` for the first frame.
  size_t receive(std::chrono::milliseconds timeout) {
    size_t frames = 0;
    while (std::optional<protocol::Frame> frame = link->receive(frames == 0 ? timeout : std::chrono::milliseconds(0))) {
      viewer.on_bytes(wire_bytes(*frame));
      ++frames;
    }
    return frames;
  }
  client::MessageSessionViewer& viewer;
  std::unique_ptr<client::Link> link;
};

client::ClientOptions options_for(StreamMode mode) {
  client::ClientOptions options{kTolerance};
  options.mode = mode;
  options.dag.max_ops = 300;  // as free_running_test.cpp: the priority traversal's fixed point is lock-step's
  return options;
}

// Frames at `camera`, moving bytes between them, until the viewer is settled.
void settle(client::MessageSessionViewer& viewer, SocketPump& pump, const Camera& camera) {
  for (int round = 0; round < kMaxRounds; ++round) {
    viewer.frame(camera);
    pump.send();
    if (viewer.settled()) return;
    pump.receive(std::chrono::milliseconds(20));
  }
  FAIL() << "not settled";
}

void opened(client::MessageSessionViewer& viewer, SocketPump& pump, const Camera& camera) {
  for (int round = 0; round < kMaxRounds; ++round) {
    const client::ViewerReport r = viewer.frame(camera);
    pump.send();
    if (!r.opening) return;
    pump.receive(std::chrono::milliseconds(20));
  }
  FAIL() << "never opened";
}

void expect_session_mode_settles_as_lock_step(StreamMode mode) {
  SCOPED_TRACE(protocol::mode_name(mode));
  const test::Fixture& f = terrain();
  test::LoopbackTcpServer server(f.catalogue);
  const std::vector<Camera> path = orbit_path(f.hierarchy, 12, 0.3f);
  client::MessageSessionViewer viewer(options_for(mode), "terrain");
  const client::ViewerReport before = viewer.frame(path[0]);
  EXPECT_TRUE(before.opening) << "nothing has come yet: no model";
  EXPECT_EQ(viewer.take_outgoing().size(), 0u) << "not connected: nothing to send";
  SocketPump pump(viewer, server.port());
  opened(viewer, pump, path[0]);

  // The flight with every answer held back: each frame returns with its request outstanding.
  for (size_t i = 0; i < path.size(); ++i) {
    const client::ViewerReport r = viewer.frame(path[i]);
    pump.send();
    EXPECT_FALSE(r.opening);
    EXPECT_GE(r.in_flight, 1u) << "frame " << i << ": nothing has been answered";
    EXPECT_EQ(r.received, 0u) << "frame " << i;
  }
  settle(viewer, pump, path.back());
  EXPECT_GT(viewer.received_total(), 0u);

  client::StreamingClient reference("127.0.0.1", server.port(), options_for(mode), "terrain");
  for (const Camera& camera : path) reference.frame(camera);
  reference.settle(path.back());
  for (int round = 0; mode == StreamMode::dag && round < 64; ++round) {
    const uint64_t faces = reference.session().mesh().face_count();
    if (reference.frame(path.back()).vsplits == 0 && reference.session().mesh().face_count() == faces) break;
  }
  const test::Faces settled = faces_by_id(viewer.session().mesh());
  if (mode == StreamMode::sender_driven || mode == StreamMode::dag) {
    EXPECT_EQ(settled, faces_by_id(reference.session().mesh())) << "the settled mesh is lock-step's";
  } else {
    EXPECT_LE(viewer.received_total(), reference.session().splits_received());
  }
  if (mode == StreamMode::sender_driven) {
    EXPECT_EQ(settled, local_faces(f.snapped, path.back(), kTolerance));
  }
}

TEST(BrowserViewers, SenderOverMessagesNeverWaitsAndSettlesAsLockStep) {
  expect_session_mode_settles_as_lock_step(StreamMode::sender_driven);
}
TEST(BrowserViewers, SenderPlainOverMessagesNeverWaits) {
  expect_session_mode_settles_as_lock_step(StreamMode::sender_plain);
}
TEST(BrowserViewers, ViewIndependentOverMessagesNeverWaits) {
  expect_session_mode_settles_as_lock_step(StreamMode::view_independent);
}
TEST(BrowserViewers, DagOverMessagesNeverWaitsAndSettlesAsLockStep) {
  expect_session_mode_settles_as_lock_step(StreamMode::dag);
}

// A lost socket: the mesh stays, nothing is in flight, nothing is sent until a new socket; then HELLO and
// an OPEN with the front held, and the session ends where an unbroken one does.
TEST(BrowserViewers, ASessionLostIsResumedOnTheNextSocket) {
  const test::Fixture& f = terrain();
  auto server = std::make_unique<test::LoopbackTcpServer>(f.catalogue);
  const uint16_t port = server->port();
  const std::vector<Camera> path = orbit_path(f.hierarchy, 10, 1.1f);
  const size_t half = path.size() / 2;
  client::MessageSessionViewer viewer(options_for(StreamMode::sender_driven), "terrain");
  auto pump = std::make_unique<SocketPump>(viewer, port);
  opened(viewer, *pump, path[0]);
  for (size_t i = 0; i < half; ++i) {
    viewer.frame(path[i]);
    pump->send();
    pump->receive(std::chrono::milliseconds(1));
  }
  settle(viewer, *pump, path[half - 1]);
  const uint64_t faces = viewer.session().mesh().face_count();

  pump.reset();
  server.reset();
  viewer.disconnected();
  const client::ViewerReport lost = viewer.frame(path[half]);
  EXPECT_EQ(lost.in_flight, 0u);
  EXPECT_FALSE(lost.satisfied);
  EXPECT_EQ(viewer.take_outgoing().size(), 0u) << "no socket: nothing to send";
  EXPECT_EQ(viewer.session().mesh().face_count() > 0, faces > 0) << "the mesh is held";

  server = std::make_unique<test::LoopbackTcpServer>(f.catalogue, server::ServerLimits{}, port);
  pump = std::make_unique<SocketPump>(viewer, port);
  for (size_t i = half; i < path.size(); ++i) {
    viewer.frame(path[i]);
    pump->send();
    pump->receive(std::chrono::milliseconds(1));
  }
  settle(viewer, *pump, path.back());
  EXPECT_EQ(faces_by_id(viewer.session().mesh()), local_faces(f.snapped, path.back(), kTolerance));
}

// Degenerate cameras: eye on the target, a zero up, an up along the view, a non-finite eye.
std::vector<Camera> degenerate_cameras(const Camera& good) {
  std::vector<Camera> out(4, good);
  for (int k = 0; k < 3; ++k) out[0].target[k] = out[0].eye[k];
  for (int k = 0; k < 3; ++k) out[1].up[k] = 0;
  for (int k = 0; k < 3; ++k) out[2].up[k] = good.target[k] - good.eye[k];
  out[3].eye[0] = std::numeric_limits<float>::quiet_NaN();
  return out;
}

// A degenerate camera does not end the viewer: that frame is refused (the report says why, the mesh and
// the counters stay), and the next good camera goes on and settles where an unbroken flight does.
TEST(BrowserViewers, ADegenerateCameraIsRefusedAndTheNextGoodOneWorks) {
  const test::Fixture& f = terrain();
  test::LoopbackTcpServer server(f.catalogue);
  const std::vector<Camera> path = orbit_path(f.hierarchy, 6, 0.3f);
  client::MessageSessionViewer viewer(options_for(StreamMode::sender_driven), "terrain");
  const client::ViewerReport early = viewer.frame(degenerate_cameras(path[0])[0]);
  EXPECT_FALSE(early.refused.empty());
  EXPECT_FALSE(early.satisfied) << "nothing shown yet";
  SocketPump pump(viewer, server.port());
  opened(viewer, pump, path[0]);
  settle(viewer, pump, path[0]);
  const test::Faces before = faces_by_id(viewer.session().mesh());
  const uint64_t up = viewer.up_bytes();
  for (const Camera& bad : degenerate_cameras(path[1])) {
    const client::ViewerReport r = viewer.frame(bad);
    pump.send();
    EXPECT_NE(r.refused.find("camera"), std::string::npos) << r.refused;
    EXPECT_EQ(r.faces, before.size());
    EXPECT_EQ(r.up_bytes, 0u);
  }
  EXPECT_EQ(viewer.up_bytes(), up) << "a refused frame asks for nothing";
  EXPECT_EQ(faces_by_id(viewer.session().mesh()), before);
  EXPECT_TRUE(viewer.settled());
  settle(viewer, pump, path[1]);
  EXPECT_TRUE(viewer.frame(path[1]).refused.empty());
  EXPECT_EQ(faces_by_id(viewer.session().mesh()), local_faces(f.snapped, path[1], kTolerance));
}

// The page's fetch for an HTTP viewer: each GET taken from the transport goes out on an HttpConnection;
// its answer is handed back by id.
struct FetchPump {
  FetchPump(client::ExternalHttpTransport& transport, const client::HttpUrl& url)
      : transport(transport), connection(url, client::HttpOptions{}) {}
  void send() {
    for (client::ExternalHttpTransport::Get& get : transport.take_gets()) {
      connection.post(get.target);
      ids.push_back(get.id);
    }
    connection.poll();
  }
  // Hands over the answers arrived; with `wait`, waits (under the connection's deadlines) for one first.
  void receive(bool wait) {
    if (ids.empty()) return;
    connection.poll();
    if (deliver() == 0 && wait) {
      connection.wait();
      deliver();
    }
  }
  size_t deliver() {
    size_t delivered = 0;
    for (; std::optional<client::HttpAnswer> answer = connection.take(); ++delivered) {
      transport.deliver(ids.front(), answer->status, std::move(answer->body));
      ids.pop_front();
    }
    return delivered;
  }
  client::ExternalHttpTransport& transport;
  client::HttpConnection connection;
  std::deque<uint32_t> ids;
};

// The flight as the page flies it (answers handed over as they come, never waited for), then settled at
// its last camera.
template <class Viewer>
void fly_http(Viewer& viewer, FetchPump& pump, const std::vector<Camera>& path) {
  for (const Camera& camera : path) {
    viewer.frame(camera);
    pump.send();
    pump.receive(false);
  }
  const Camera& camera = path.back();
  for (int round = 0; round < kMaxRounds; ++round) {
    const client::ViewerReport r = viewer.frame(camera);
    pump.send();
    if (!r.opening && r.satisfied && r.in_flight == 0 && pump.ids.empty() && !viewer.in_motion()) return;
    pump.receive(true);
  }
  FAIL() << "not settled";
}

TEST(BrowserViewers, ReceiverOverFetchOpensWithoutWaitingAndSettlesOnLocalRefinement) {
  const test::Fixture& f = terrain();
  test::LoopbackHttpServer server(f.catalogue);
  const std::vector<Camera> path = orbit_path(f.hierarchy, 10, 0.3f);
  auto owned = std::make_unique<client::ExternalHttpTransport>();
  client::ExternalHttpTransport& transport = *owned;
  client::ReceiverOptions options;
  options.tolerance = kTolerance;
  client::ReceiverViewer viewer(std::move(owned), std::make_unique<client::FaceIdImportance>(), options, "terrain");
  FetchPump pump(transport, server.url());
  // Opening with its answers held back: frames return at once and report it.
  for (int i = 0; i < 3; ++i) {
    EXPECT_TRUE(viewer.frame(path[0]).opening);
    pump.send();
  }
  EXPECT_EQ(pump.ids.size(), 1u) << "the catalogue first: it names the version whose base and tables come next";
  fly_http(viewer, pump, path);
  EXPECT_EQ(faces_by_id(viewer.client().session().mesh()), local_faces(f.snapped, path.back(), kTolerance));
  EXPECT_THROW(transport.wait(), Error) << "this transport cannot wait";
}

// Settled by frames alone (satisfied, nothing in flight, not in motion), with geomorphs and without, the
// mesh is lock-step's at the last camera: not in motion means the wanted level is shown, not merely some
// whole level on the way to it. A degenerate camera on the way changes nothing.
void expect_multilevel_settles_on_lock_steps_level(uint32_t morph_frames) {
  SCOPED_TRACE("morph_frames " + std::to_string(morph_frames));
  const test::Fixture& f = terrain();
  test::LoopbackHttpServer server(f.catalogue);
  std::vector<Camera> path = orbit_path(f.hierarchy, 10, 0.3f);
  auto owned = std::make_unique<client::ExternalHttpTransport>();
  client::ExternalHttpTransport& transport = *owned;
  client::MultilevelOptions options;
  options.morph_frames = morph_frames;
  client::MultilevelViewer viewer(std::move(owned), options, "terrain");
  FetchPump pump(transport, server.url());
  EXPECT_TRUE(viewer.frame(path[0]).opening);
  pump.send();
  const std::vector<Camera> bad = degenerate_cameras(path[3]);
  path.insert(path.begin() + 3, bad.begin(), bad.end());
  fly_http(viewer, pump, path);

  client::MultilevelViewer reference("http://127.0.0.1:" + std::to_string(server.port()), options,
                                     client::Pacing::lock_step, "terrain");
  for (const Camera& camera : path) reference.frame(camera);
  reference.settle(path.back());
  const Mesh got = viewer.mesh(), want = reference.mesh();
  EXPECT_GT(got.face_count(), 0u);
  EXPECT_EQ(got.positions, want.positions);
  EXPECT_EQ(got.indices, want.indices);
}

TEST(BrowserViewers, MultilevelOverFetchSettlesOnLockStepsLevel) { expect_multilevel_settles_on_lock_steps_level(0); }
TEST(BrowserViewers, MultilevelWithGeomorphsSettlesOnLockStepsLevel) {
  expect_multilevel_settles_on_lock_steps_level(client::kDefaultGeomorphFrames);
}

}  // namespace
}  // namespace pms
