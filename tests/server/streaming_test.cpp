// Sender-driven streaming over real loopback TCP (properties 3 and 4, docs/architecture.md): the client's mesh
// equals local refinement of the same view, a second lap costs nothing, a resumed session ends where an
// unbroken one does, many clients at once all succeed, and hostile input only ends its own session.
// The view-independent baseline (kim-lee-kobbelt §8 Fig. 9): PM order, prefix by prefix.
#include <utility>  // before asio with C++20

#include <gtest/gtest.h>
#include <algorithm>
#include <array>
#include <atomic>
#include <boost/asio.hpp>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <map>
#include <optional>
#include <thread>

#include "builder/build.h"
#include "client/link.h"
#include "client/streaming_client.h"
#include "client/transport.h"
#include "io/mesh.h"
#include "io/shapes.h"
#include "protocol/client_messages.h"
#include "protocol/framing.h"
#include "protocol/message_types.h"
#include "protocol/model_messages.h"
#include "protocol/server_messages.h"
#include "protocol/stream_context.h"
#include "server/catalogue.h"
#include "server/limits.h"
#include "server/tcp_server.h"
#include "spm/adapt.h"
#include "spm/hierarchy.h"
#include "spm/refine_info.h"
#include "spm/selective_mesh.h"
#include "spm/split_record.h"
#include "spm/stream_order.h"
#include "spm/vertex_id.h"
#include "streaming_fixture.h"
#include "test_support.h"

namespace pms {
namespace {

using test::faces_by_id;
using test::Fixture;
using test::local_faces;
using test::make_fixture;
using test::orbit_path;
using test::send_raw;

using Server = test::LoopbackTcpServer;

const Fixture& terrain() {
  return test::terrain_fixture(60000, 5);
}

TEST(Streaming, ClientMeshEqualsLocalRefinementAndASecondLapIsFree) {
  const Fixture& f = terrain();
  Server server(f.catalogue);
  client::StreamingClient client("127.0.0.1", server.tcp.port(), client::ClientOptions{1.0f});
  const protocol::Catalogue list = client.list();
  ASSERT_EQ(list.models.size(), 1u);
  EXPECT_EQ(list.models[0].name, "terrain");
  client.open("terrain");
  const std::vector<Camera> path = orbit_path(f.hierarchy, 12, 0.3f);
  uint64_t lap1_down = 0, requests = 0;
  for (const Camera& camera : path) {
    const client::FrameReport r = client.frame(camera);
    lap1_down += r.down_bytes;
    requests += r.requested;
    EXPECT_EQ(faces_by_id(client.session().mesh()), local_faces(f.snapped, camera, 1.0f))
        << "frame " << r.frame << " differs from local refinement";
  }
  EXPECT_GT(lap1_down, 0u);
  EXPECT_GT(requests, 0u);
  uint64_t lap2_down = 0, lap2_up = 0;
  for (const Camera& camera : path) {
    const client::FrameReport r = client.frame(camera);
    lap2_down += r.down_bytes;
    lap2_up += r.up_bytes;
  }
  EXPECT_EQ(lap2_down, 0u) << "property 4: every vsplit crosses the network once";
  EXPECT_EQ(lap2_up, 0u) << "the client asks only when its own hierarchy cannot satisfy the view";
}

TEST(Streaming, ResumedSessionEndsWhereAnUnbrokenOneDoes) {
  const Fixture& f = terrain();
  Server server(f.catalogue);
  const std::vector<Camera> path = orbit_path(f.hierarchy, 10, 1.1f);
  client::StreamingClient client("127.0.0.1", server.tcp.port(), client::ClientOptions{0.5f});
  client.open("terrain");
  for (size_t i = 0; i < path.size() / 2; ++i) client.frame(path[i]);
  const uint64_t before = client.session().splits_received();
  // The connection drops; the client reconnects and resumes with its known leaves.
  client.resume("127.0.0.1", server.tcp.port());
  for (size_t i = path.size() / 2; i < path.size(); ++i) client.frame(path[i]);
  EXPECT_GT(client.session().splits_received(), before);
  EXPECT_EQ(faces_by_id(client.session().mesh()), local_faces(f.snapped, path.back(), 0.5f));
  // Nothing was sent twice: a fresh session to the same last view receives at most as many packets.
  client::StreamingClient fresh("127.0.0.1", server.tcp.port(), client::ClientOptions{0.5f});
  fresh.open("terrain");
  for (const Camera& camera : path) fresh.frame(camera);
  EXPECT_EQ(client.session().splits_received(), fresh.session().splits_received());
}

// A session that goes quiet parks its front coded (ServerLimits::park_after_ms) and decodes it for the next
// VIEW: the flight goes on as on a server that keeps the tags throughout, split for split.
TEST(Streaming, AParkedFrontAnswersAsTheTagsDo) {
  const Fixture& f = terrain();
  server::ServerLimits parking, tags;
  parking.park_after_ms = 20;
  tags.compact_fronts = false;
  Server parking_server(f.catalogue, parking), tags_server(f.catalogue, tags);
  const std::vector<Camera> path = orbit_path(f.hierarchy, 8, 0.7f);
  client::StreamingClient parked("127.0.0.1", parking_server.tcp.port(), client::ClientOptions{1.0f});
  client::StreamingClient kept("127.0.0.1", tags_server.tcp.port(), client::ClientOptions{1.0f});
  parked.open("terrain");
  kept.open("terrain");
  for (const Camera& camera : path) {
    const uint64_t parked_down = parked.frame(camera).down_bytes, kept_down = kept.frame(camera).down_bytes;
    EXPECT_EQ(parked_down, kept_down);
    EXPECT_EQ(faces_by_id(parked.session().mesh()), local_faces(f.snapped, camera, 1.0f));
    std::this_thread::sleep_for(std::chrono::milliseconds(60));  // past park_after_ms: the next VIEW decodes
  }
  EXPECT_EQ(parked.session().splits_received(), kept.session().splits_received());
  EXPECT_GE(parking_server.tcp.stats().fronts_parked.load(), path.size() - 1);
  EXPECT_EQ(tags_server.tcp.stats().fronts_parked.load(), 0u);
}

TEST(Streaming, BunnyAlongAPathMatchesLocalRefinement) {
  PMS_REQUIRE_SHARED_MODEL(file, "bunny.ply.xz");
  Mesh mesh = load_mesh(file.string());
  clean_mesh(mesh);
  const Fixture f = make_fixture(mesh, "bunny");
  Server server(f.catalogue);
  client::StreamingClient client("127.0.0.1", server.tcp.port(), client::ClientOptions{1.0f});
  client.open("bunny");
  const std::vector<Camera> path = orbit_path(f.hierarchy, 8, 0.0f);
  for (const Camera& camera : path) client.frame(camera);
  EXPECT_EQ(faces_by_id(client.session().mesh()), local_faces(f.snapped, path.back(), 1.0f));
}

TEST(Streaming, TwentyConcurrentClientsWithDifferentPathsAllSucceed) {
  const Fixture& f = terrain();
  Server server(f.catalogue);
  std::vector<std::thread> clients;
  std::vector<int> ok(20, 0);
  for (int i = 0; i < 20; ++i)
    clients.emplace_back([&, i] {
      client::StreamingClient client("127.0.0.1", server.tcp.port(), client::ClientOptions{1.0f});
      client.open("terrain");
      const std::vector<Camera> path = orbit_path(f.hierarchy, 6, 0.31f * float(i));
      for (const Camera& camera : path) client.frame(camera);
      ok[size_t(i)] = faces_by_id(client.session().mesh()) == local_faces(f.snapped, path.back(), 1.0f);
    });
  for (std::thread& t : clients) t.join();
  for (int i = 0; i < 20; ++i) EXPECT_TRUE(ok[size_t(i)]) << "client " << i;
}

// ---- view-independent mode ------------------------------------------------------------------------------

client::ClientOptions vi_options(float tolerance) {
  client::ClientOptions options{tolerance};
  options.mode = protocol::StreamMode::view_independent;
  return options;
}

// A mesh as a sorted list of triangles of positions (vertex numbering differs between two builds of
// the same mesh; positions are the wire's snapped ones on both sides, so they compare exactly).
std::vector<std::array<float, 9>> triangles(const MeshArrays& mesh) {
  std::vector<std::array<float, 9>> out;
  for (size_t f = 0; f < mesh.indices.size(); f += 3) {
    std::array<std::array<float, 3>, 3> corners;
    for (int k = 0; k < 3; ++k) std::copy_n(&mesh.positions[3 * size_t(mesh.indices[f + k])], 3, corners[k].begin());
    std::rotate(corners.begin(), std::min_element(corners.begin(), corners.end()), corners.end());
    std::array<float, 9> t;
    for (int k = 0; k < 3; ++k) std::copy_n(corners[k].begin(), 3, t.begin() + 3 * k);
    out.push_back(t);
  }
  std::sort(out.begin(), out.end());
  return out;
}

TEST(Streaming, ViewIndependentClientHoldsThePmOrderPrefix) {
  const Fixture& f = terrain();
  const ModelData model = model_of(f.snapped);
  Server server(f.catalogue);
  const std::vector<Camera> path = orbit_path(f.hierarchy, 8, 0.7f);
  client::StreamingClient client("127.0.0.1", server.tcp.port(), vi_options(1.0f));
  client.open("terrain");
  uint64_t lap1_down = 0, previous = 0;
  for (const Camera& camera : path) {
    const client::FrameReport r = client.frame(camera);
    lap1_down += r.down_bytes;
    EXPECT_TRUE(r.requested) << "a vi client asks every frame";
    const uint64_t k = client.session().splits_received();
    EXPECT_GE(k, previous);
    previous = k;
    MeshArrays mesh;
    client.session().mesh().extract(mesh);
    EXPECT_EQ(triangles(mesh), triangles(refine_in_stream_order(model, k))) << "frame " << r.frame << ", K = " << k;
  }
  EXPECT_GT(previous, 0u);
  EXPECT_LT(previous, model.split_order.size()) << "the path should not need the whole model at τ = 1";
  EXPECT_GT(lap1_down, 0u);
  // Lap 2: nothing new. Each VIEW is answered by one empty final VSPLITS (header + 9 bytes).
  uint64_t lap2_splits = 0, lap2_down = 0;
  for (const Camera& camera : path) {
    const client::FrameReport r = client.frame(camera);
    lap2_splits += r.vsplits;
    lap2_down += r.down_bytes;
  }
  EXPECT_EQ(lap2_splits, 0u) << "property 4: every vsplit crosses the network once";
  EXPECT_EQ(lap2_down, path.size() * (protocol::kFrameHeaderBytes + 9)) << "only the empty final batches";
}

TEST(Streaming, ViewIndependentPacketsComeInPmOrderWithoutRefinementInfo) {
  const Fixture& f = terrain();
  const ModelData model = model_of(f.snapped);
  Server server(f.catalogue);
  client::Link link("127.0.0.1", server.tcp.port());
  const std::chrono::seconds timeout(30);
  auto expect = [&](protocol::MessageType type) {
    std::optional<protocol::Frame> frame = link.receive(timeout);
    EXPECT_TRUE(frame && frame->type == type);
    return frame ? std::move(*frame) : protocol::Frame{};
  };
  link.send(protocol::encode(protocol::Hello{protocol::kProtocolVersion, "vi"}));
  expect(protocol::MessageType::hello_ok);
  link.send(protocol::encode(protocol::Open{"terrain", {}, protocol::StreamMode::view_independent}));
  protocol::StreamContext context =
      protocol::stream_context(protocol::decode_base(expect(protocol::MessageType::base).payload));
  context.has_refinement = false;
  uint64_t next = 0;
  const std::vector<Camera> path = orbit_path(f.hierarchy, 6, 2.1f);
  for (uint32_t frame = 1; frame <= path.size(); ++frame) {
    link.send(protocol::encode(protocol::View{path[frame - 1], 1.0f, frame}));
    for (;;) {
      const protocol::Frame message = expect(protocol::MessageType::vsplits);
      ASSERT_EQ(message.type, protocol::MessageType::vsplits);
      const protocol::VSplits batch = protocol::decode_vsplits(message.payload, context);
      for (const SplitRecord& split : batch.splits) {
        ASSERT_LT(next, model.split_order.size());
        EXPECT_EQ(split.vs, model.id(model.split_order[next])) << "packet " << next << " is out of PM order";
        EXPECT_EQ(split.info_t, RefineInfo{});
        ++next;
      }
      if (batch.final && batch.frame == frame) break;
    }
  }
  EXPECT_GT(next, 0u);
}

TEST(Streaming, ViewIndependentNeedsAtLeastTheBytesOfSenderDriven) {
  const Fixture& f = terrain();
  Server server(f.catalogue);
  const Camera close = orbit_path(f.hierarchy, 8, 0.4f).back();
  client::StreamingClient sender("127.0.0.1", server.tcp.port(), client::ClientOptions{1.0f});
  sender.open("terrain");
  sender.frame(close);
  client::StreamingClient vi("127.0.0.1", server.tcp.port(), vi_options(1.0f));
  vi.open("terrain");
  vi.frame(close);
  EXPECT_GT(sender.counters().bytes_down, 0u);
  EXPECT_GE(vi.counters().bytes_down, sender.counters().bytes_down);
  // Every split the view-dependent client needed is in the vi client's prefix.
  EXPECT_GE(vi.session().splits_received(), sender.session().splits_received());
}

TEST(Streaming, HostileInputGetsAnErrorWhileAGoodSessionGoesOn) {
  const Fixture& f = terrain();
  server::ServerLimits limits;
  limits.max_client_message = 1 << 16;
  Server server(f.catalogue, limits);
  const uint16_t port = server.tcp.port();
  const auto hello = protocol::encode(protocol::Hello{protocol::kProtocolVersion, "raw"});
  protocol::View view;
  view.camera = orbit_path(f.hierarchy, 2, 0)[0];

  std::thread good([&] {
    client::StreamingClient client("127.0.0.1", port, client::ClientOptions{1.0f});
    client.open("terrain");
    for (const Camera& camera : orbit_path(f.hierarchy, 8, 2.0f)) client.frame(camera);
    EXPECT_GT(client.session().splits_received(), 0u);
  });
  using protocol::ErrorCode;
  EXPECT_EQ(send_raw(port, {{3, 0, 0, 0, 0x42, 1, 2, 3}}), ErrorCode::bad_message) << "unknown message type";
  EXPECT_EQ(send_raw(port, {{1, 2, 3, 4, 5, 6, 7, 8, 9}}), ErrorCode::too_large) << "garbage length";
  EXPECT_EQ(send_raw(port, {{0xFF, 0xFF, 0xFF, 0x7F, 0x01}}), ErrorCode::too_large) << "oversized frame";
  EXPECT_EQ(send_raw(port, {protocol::encode(view)}), ErrorCode::out_of_order) << "VIEW before HELLO";
  EXPECT_EQ(send_raw(port, {hello, protocol::encode(view)}), ErrorCode::out_of_order) << "VIEW before OPEN";
  EXPECT_EQ(send_raw(port, {hello, protocol::encode(protocol::Open{"nope", {}})}), ErrorCode::unknown_model);
  EXPECT_EQ(send_raw(port, {protocol::encode(protocol::Hello{99, "future"})}), ErrorCode::unsupported_version);
  // A resume front naming nodes deeper than the model has.
  protocol::Open deep{"terrain", {}};
  const uint32_t roots = f.hierarchy.root_count;
  for (uint32_t t = 0; t < roots; ++t) {
    VertexId v{t, 1};
    for (int d = 0; d < 40; ++d) {
      deep.resume.push_back(v.child(1));
      v = v.child(0);
    }
    deep.resume.push_back(v);
  }
  EXPECT_EQ(send_raw(port, {hello, protocol::encode(deep)}), ErrorCode::bad_id);
  // Resume is sender-driven only.
  protocol::Open resume_vi{"terrain", {}, protocol::StreamMode::view_independent};
  for (uint32_t t = 0; t < roots; ++t) resume_vi.resume.push_back({t, 1});
  EXPECT_EQ(send_raw(port, {hello, protocol::encode(resume_vi)}), ErrorCode::bad_message);
  good.join();
}

// HELLO, OPEN and one VIEW on a raw connection, then the answer read `chunk` bytes at a time with `pause`
// between reads; returns the ids of the splits, in order, up to the VIEW's final batch.
std::vector<VertexId> raw_answer(uint16_t port, const Camera& camera, float tolerance, size_t chunk,
                                 std::chrono::milliseconds pause) {
  namespace asio = boost::asio;
  asio::io_context io;
  asio::ip::tcp::socket socket(io);
  socket.open(asio::ip::tcp::v4());
  socket.set_option(asio::socket_base::receive_buffer_size(int(chunk)));  // before connect: a small window
  socket.connect({asio::ip::make_address("127.0.0.1"), port});
  for (const auto& m :
       {protocol::encode(protocol::Hello{protocol::kProtocolVersion, "raw"}),
        protocol::encode(protocol::Open{"terrain", {}}), protocol::encode(protocol::View{camera, tolerance, 1})})
    asio::write(socket, asio::buffer(m));
  protocol::FrameReader reader;
  client::ClientSession session;  // decodes split records against the hierarchy they make
  std::vector<VertexId> ids;
  std::vector<uint8_t> buffer(chunk);
  for (;;) {
    std::this_thread::sleep_for(pause);
    const size_t n = socket.read_some(asio::buffer(buffer));
    reader.feed(buffer.data(), n);
    protocol::Frame frame;
    while (reader.next(frame)) {
      if (frame.type == protocol::MessageType::base) session.on_base(protocol::decode_base(frame.payload));
      if (frame.type == protocol::MessageType::codec)
        session.on_codec(protocol::decode_codec(frame.payload, session.context()));
      if (frame.type != protocol::MessageType::vsplits) continue;
      const protocol::VSplits batch = protocol::decode_vsplits(frame.payload, session.context());
      session.on_vsplits(batch);
      for (const SplitRecord& split : batch.splits) ids.push_back(split.vs);
      if (batch.final) return ids;
    }
  }
}

TEST(Streaming, ASlowReaderGetsItsWholeAnswerAndStallsNobody) {
  const Fixture& f = terrain();
  server::ServerLimits limits;
  limits.threads = 1;              // an I/O thread blocked on a full socket would stall every session
  limits.send_queue_bytes = 2048;  // back-pressure after a frame or two,
  limits.send_burst_bytes = 4096;  // and short bursts straight into the socket
  Server server(f.catalogue, limits);
  const uint16_t port = server.tcp.port();
  const Camera close = orbit_path(f.hierarchy, 8, 0.4f).back();
  std::vector<VertexId> slow;
  std::thread reader([&] { slow = raw_answer(port, close, 0.25f, 4096, std::chrono::milliseconds(2)); });
  // Meanwhile another session streams a whole path on the same, single I/O thread.
  client::StreamingClient client("127.0.0.1", port, client::ClientOptions{1.0f});
  client.open("terrain");
  for (const Camera& camera : orbit_path(f.hierarchy, 8, 2.0f)) client.frame(camera);
  EXPECT_GT(client.session().splits_received(), 0u);
  reader.join();
  // The same answer as a reader that takes everything at once.
  const std::vector<VertexId> fast = raw_answer(port, close, 0.25f, 1 << 20, std::chrono::milliseconds(0));
  EXPECT_GT(slow.size(), 2000u) << "the answer should be many times the socket buffers";
  EXPECT_TRUE(slow == fast);
}

TEST(Streaming, ServerLossIsAClearError) {
  const Fixture& f = terrain();
  auto server = std::make_unique<Server>(f.catalogue);
  const uint16_t port = server->tcp.port();
  client::StreamingClient client("127.0.0.1", port, client::ClientOptions{1.0f});
  client.open("terrain");
  server.reset();
  try {
    for (const Camera& camera : orbit_path(f.hierarchy, 6, 0.0f)) client.frame(camera);
    FAIL() << "no error after the server went away";
  } catch (const client::ConnectionError& e) {
    EXPECT_NE(std::string(e.what()).find("connection"), std::string::npos) << e.what();
  }
}

// With reconnect attempts, a frame that finds the server gone waits for one on the same port, resumes with
// its leaves (kim-lee-kobbelt §5.3) and the path ends where an unbroken session does.
TEST(Streaming, ReconnectResumesOnARestartedServer) {
  const Fixture& f = terrain();
  auto server = std::make_unique<Server>(f.catalogue);
  const uint16_t port = server->tcp.port();
  const std::vector<Camera> path = orbit_path(f.hierarchy, 10, 1.1f);
  const size_t half = path.size() / 2;
  client::ClientOptions options{0.5f};
  options.reconnect_attempts = 8;
  options.reconnect_delay = std::chrono::milliseconds(20);
  std::vector<uint32_t> attempts;
  std::vector<std::string> reasons;
  std::atomic<size_t> told{0};
  options.on_reconnect = [&](const std::string& reason, uint32_t attempt) {
    reasons.push_back(reason);
    attempts.push_back(attempt);
    ++told;
  };
  client::StreamingClient client("127.0.0.1", port, options);
  client.open("terrain");
  for (size_t i = 0; i < half; ++i) client.frame(path[i]);
  server.reset();
  // Back on the same port once the client has been refused at least once.
  std::thread restart([&] {
    while (told < 2) std::this_thread::sleep_for(std::chrono::milliseconds(2));
    server = std::make_unique<Server>(f.catalogue, server::ServerLimits{}, port);
  });
  client.frame(path[half]);
  restart.join();
  for (size_t i = half + 1; i < path.size(); ++i) client.frame(path[i]);
  ASSERT_GE(attempts.size(), 2u);
  for (size_t i = 0; i < attempts.size(); ++i) EXPECT_EQ(attempts[i], i + 1);
  EXPECT_NE(reasons[0].find("server: connection lost"), std::string::npos) << reasons[0];
  EXPECT_NE(reasons[1].find("cannot connect"), std::string::npos) << "then why the last attempt failed: " << reasons[1];
  EXPECT_EQ(faces_by_id(client.session().mesh()), local_faces(f.snapped, path.back(), 0.5f));
}

}  // namespace
}  // namespace pms
