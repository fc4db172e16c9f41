// Sender-driven streaming over real loopback TCP (DESIGN.md §6 properties 3 and 4): the client's mesh
// equals local refinement of the same view, a second lap costs nothing, a resumed session ends where an
// unbroken one does, many clients at once all succeed, and hostile input only ends its own session.
#include <gtest/gtest.h>

#include <utility>  // before asio with C++20

#include <boost/asio.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <map>
#include <thread>

#include "build/build.h"
#include "client/client.h"
#include "io/mesh.h"
#include "io/shapes.h"
#include "refine/adapt.h"
#include "server/server.h"
#include "test_support.h"

namespace pms {
namespace {

namespace fs = std::filesystem;
using Faces = std::vector<std::array<VertexId, 3>>;

struct Fixture {
  Hierarchy hierarchy;  // as built
  Hierarchy snapped;    // positions as clients receive them
  std::string path;     // the .pms file served
  std::shared_ptr<const server::Catalogue> catalogue;
  std::string name;
};

Fixture make_fixture(const Mesh& mesh, const std::string& name) {
  Fixture f;
  BuildResult built = build_progressive_mesh(mesh, BuildOptions{});
  f.hierarchy = std::move(built.hierarchy);
  f.name = name;
  f.path = (test::temp_dir() / (name + ".pms")).string();
  write_pms(f.path, f.hierarchy, built.stats);
  f.catalogue = server::Catalogue::open({f.path});
  f.snapped = f.hierarchy;
  const protocol::PositionGrid grid = f.catalogue->find(name)->context.grid;
  for (size_t n = 0; n < f.snapped.node_count(); ++n)
    protocol::snap_position(grid, &f.hierarchy.position[3 * n], &f.snapped.position[3 * n]);
  return f;
}

// Frames circling the model and closing in on it, so later frames need detail earlier ones did not.
std::vector<Camera> orbit_path(const Hierarchy& h, int frames, float phase) {
  float centre[3], extent = 0;
  for (int k = 0; k < 3; ++k) {
    centre[k] = 0.5f * (h.bbox_min[k] + h.bbox_max[k]);
    extent = std::max(extent, h.bbox_max[k] - h.bbox_min[k]);
  }
  std::vector<Camera> path;
  for (int i = 0; i < frames; ++i) {
    const float t = float(i) / float(std::max(1, frames - 1));
    const float angle = phase + 2.5f * t;
    const float distance = extent * (2.2f - 1.5f * t);
    Camera c;
    c.eye[0] = centre[0] + distance * std::cos(angle);
    c.eye[1] = centre[1] + 0.4f * extent;
    c.eye[2] = centre[2] + distance * std::sin(angle);
    std::copy_n(centre, 3, c.target);
    c.width = 320;
    c.height = 240;
    path.push_back(c);
  }
  return path;
}

Faces faces_by_id(SelectiveMesh& mesh) {
  Faces faces;
  const VertexHierarchy& h = mesh.hierarchy();
  for (uint32_t f = 0; f < mesh.face_capacity(); ++f) {
    if (!mesh.face_alive(f)) continue;
    std::array<VertexId, 3> face = {h.id(mesh.face(f)[0]), h.id(mesh.face(f)[1]), h.id(mesh.face(f)[2])};
    auto less = [](VertexId a, VertexId b) { return a.tree < b.tree || (a.tree == b.tree && a.node < b.node); };
    std::rotate(face.begin(), std::min_element(face.begin(), face.end(), less), face.end());
    faces.push_back(face);
  }
  std::sort(faces.begin(), faces.end(), [](const auto& a, const auto& b) {
    for (int k = 0; k < 3; ++k) {
      if (a[k].tree != b[k].tree) return a[k].tree < b[k].tree;
      if (a[k].node != b[k].node) return a[k].node < b[k].node;
    }
    return false;
  });
  return faces;
}

// Local refinement of the same model (positions as the wire carries them) for one view.
Faces local_faces(const Hierarchy& snapped, const Camera& camera, float tolerance) {
  const ModelView model = view_of(snapped);
  VertexHierarchy hierarchy = VertexHierarchy::from_model(model);
  SelectiveMesh mesh(hierarchy, model.base_faces);
  SelectiveRefinement refinement(mesh, model.scale, AdaptOptions{tolerance, 0, 0});
  refinement.set_view(make_view(camera, model.bbox_min, model.bbox_max));
  refinement.converge([&](std::span<const uint32_t> leaves) { return add_model_splits(hierarchy, model, leaves); });
  return faces_by_id(mesh);
}

struct Server {
  explicit Server(std::shared_ptr<const server::Catalogue> catalogue, server::ServerLimits limits = {})
      : tcp(std::move(catalogue), limits, "127.0.0.1", 0) {
    tcp.start();
  }
  server::TcpServer tcp;
};

const Fixture& terrain() {
  static const Fixture f = make_fixture(make_terrain(60000, 5), "terrain");
  return f;
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

// A raw connection that sends bytes and reads until the server closes; returns the ERROR's code.
std::optional<protocol::ErrorCode> send_raw(uint16_t port, const std::vector<std::vector<uint8_t>>& messages) {
  namespace asio = boost::asio;
  asio::io_context io;
  asio::ip::tcp::socket socket(io);
  socket.connect({asio::ip::make_address("127.0.0.1"), port});
  boost::system::error_code ec;
  for (const auto& m : messages) asio::write(socket, asio::buffer(m), ec);
  protocol::FrameReader reader;
  std::array<uint8_t, 4096> buffer;
  std::optional<protocol::ErrorCode> code;
  for (;;) {
    const size_t n = socket.read_some(asio::buffer(buffer), ec);
    if (ec) break;
    reader.feed(buffer.data(), n);
    protocol::Frame frame;
    while (reader.next(frame))
      if (frame.type == protocol::MessageType::error) code = protocol::decode_error(frame.payload).code;
  }
  return code;
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
  good.join();
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
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("connection"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace pms
