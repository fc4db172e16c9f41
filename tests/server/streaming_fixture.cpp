// Helpers the server tests share (streaming_fixture.h).
#include "streaming_fixture.h"

#include <gtest/gtest.h>

#include <utility>  // before asio with C++20

#include <algorithm>
#include <array>
#include <boost/asio.hpp>
#include <cmath>
#include <map>
#include <mutex>
#include <span>

#include "builder/build.h"
#include "client/local_transport.h"
#include "io/shapes.h"
#include "protocol/framing.h"
#include "protocol/message_types.h"
#include "protocol/position_grid.h"
#include "protocol/server_messages.h"
#include "protocol/url_segment.h"
#include "server/catalogue.h"
#include "spm/adapt.h"
#include "spm/hierarchy.h"
#include "spm/octahedral_normal.h"
#include "spm/pms_file.h"
#include "spm/selective_mesh.h"
#include "spm/vertex_hierarchy.h"
#include "spm/vertex_id.h"
#include "test_support.h"

namespace pms::test {

std::string model_url(const server::Catalogue& catalogue, const std::string& name) {
  if (const server::ServedModel* model = catalogue.find(name)) return protocol::model_path(name, model->version);
  if (const server::ServedMultilevel* model = catalogue.find_multilevel(name))
    return protocol::model_path(name, model->version);
  ADD_FAILURE() << "no model named " << name;
  return {};
}

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
  for (size_t n = 0; n < f.snapped.normals.size() / 3; ++n) {
    uint16_t q[2];
    encode_normal(&f.hierarchy.normals[3 * n], q);
    decode_normal(q, &f.snapped.normals[3 * n]);
  }
  return f;
}

const Fixture& terrain_fixture(uint64_t faces, uint32_t seed) {
  static std::mutex mutex;
  static std::map<std::pair<uint64_t, uint32_t>, std::unique_ptr<const Fixture>> built;
  const std::lock_guard lock(mutex);
  auto& fixture = built[{faces, seed}];
  if (!fixture) fixture = std::make_unique<const Fixture>(make_fixture(make_terrain(faces, seed), "terrain"));
  return *fixture;
}

const Fixture& file_fixture(const std::string& mesh_path, const std::string& name) {
  static std::mutex mutex;
  static std::map<std::string, std::unique_ptr<const Fixture>> built;
  const std::lock_guard lock(mutex);
  auto& fixture = built[mesh_path];
  if (!fixture) {
    Mesh mesh = load_mesh(mesh_path);
    clean_mesh(mesh);
    fixture = std::make_unique<const Fixture>(make_fixture(mesh, name));
  }
  return *fixture;
}

const Fixture& attributed_terrain() {
  static const Fixture f = [] {
    Mesh mesh = make_terrain(8000, 9);
    const size_t n = mesh.vertex_count();
    mesh.normals.resize(3 * n);
    mesh.colors.resize(4 * n);
    for (size_t v = 0; v < n; ++v) {
      const float* p = &mesh.positions[3 * v];
      float normal[3] = {std::sin(3 * p[0]), 2.0f, std::cos(2 * p[2])}, length = 0;
      for (float c : normal) length += c * c;
      for (int k = 0; k < 3; ++k) {
        mesh.normals[3 * v + size_t(k)] = normal[k] / std::sqrt(length);
        mesh.colors[4 * v + size_t(k)] = uint8_t(127.5f + 127.5f * std::sin(float(k + 1) * p[k]));
      }
      mesh.colors[4 * v + 3] = uint8_t(v % 7 == 0 ? 128 : 255);
    }
    return make_fixture(mesh, "attributed");
  }();
  return f;
}

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

Vertices vertices_by_id(SelectiveMesh& mesh) {
  Vertices vertices;
  const VertexHierarchy& h = mesh.hierarchy();
  for (uint32_t slot : mesh.active_vertices()) {
    VertexValues& v = vertices.emplace_back();
    v.id = h.id(slot);
    std::copy_n(h.position(slot), 3, v.position);
    if (h.has_normals()) std::copy_n(h.normal(slot), 3, v.normal);
    if (h.has_colors()) std::copy_n(h.color(slot), 4, v.color);
  }
  std::sort(vertices.begin(), vertices.end(), [](const VertexValues& a, const VertexValues& b) {
    return a.id.tree < b.id.tree || (a.id.tree == b.id.tree && a.id.node < b.id.node);
  });
  return vertices;
}

namespace {

// `read` of the mesh local refinement of the same model makes for one view.
template <class Read>
auto refine_locally(const Hierarchy& snapped, const Camera& camera, float tolerance, Read read) {
  const ModelData model = model_of(snapped);
  VertexHierarchy hierarchy = VertexHierarchy::from_model(model);
  SelectiveMesh mesh(hierarchy, model.base_faces);
  SelectiveRefinement refinement(mesh, model.scale, AdaptOptions{tolerance, 0, 0});
  refinement.set_view(make_view(camera, model.bbox_min, model.bbox_max));
  refinement.converge([&](std::span<const uint32_t> leaves) { return add_model_splits(hierarchy, model, leaves); });
  return read(mesh);
}

}  // namespace

void LocalMeshCheck::check(size_t viewer, SelectiveMesh& mesh, const Camera& last) {
  const bool same = faces_by_id(mesh) == local_faces(snapped_, last, tolerance_);
  const std::lock_guard lock(mutex_);
  if (!same) differ_.push_back(viewer);
}

::testing::AssertionResult LocalMeshCheck::all_same() const {
  const std::lock_guard lock(mutex_);
  if (differ_.empty()) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << differ_.size() << " viewers' meshes differ from local refinement, the first "
                                       << *std::min_element(differ_.begin(), differ_.end());
}

Faces local_faces(const Hierarchy& snapped, const Camera& camera, float tolerance) {
  return refine_locally(snapped, camera, tolerance, [](SelectiveMesh& mesh) { return faces_by_id(mesh); });
}

Vertices local_vertices(const Hierarchy& snapped, const Camera& camera, float tolerance) {
  return refine_locally(snapped, camera, tolerance, [](SelectiveMesh& mesh) { return vertices_by_id(mesh); });
}

Image picture(const SelectiveMesh& mesh, const Camera& camera, const Hierarchy& model) {
  MeshArrays arrays;
  mesh.extract(arrays);
  return render({arrays.positions, arrays.indices, arrays.colors}, make_view(camera, model.bbox_min, model.bbox_max));
}

Image local_picture(const Hierarchy& snapped, const Camera& camera, float tolerance) {
  return refine_locally(snapped, camera, tolerance,
                        [&](SelectiveMesh& mesh) { return picture(mesh, camera, snapped); });
}

InProcess in_process(const Fixture& f, const client::ClientOptions& options, const server::ServerLimits& limits) {
  InProcess p;
  p.session = std::make_shared<server::Session>(f.catalogue, limits);
  client::LocalEndpoint endpoint;
  endpoint.receive = [s = p.session](protocol::Frame frame) { s->receive(std::move(frame)); };
  endpoint.next_frame = [s = p.session]() -> server::Buffer {
    while (s->outbox().empty())
      if (!s->pump()) return nullptr;
    server::Buffer frame = std::move(s->outbox().front());
    s->outbox().pop_front();
    return frame;
  };
  p.client = std::make_unique<client::StreamingClient>(
      std::make_unique<client::LocalTransport>(std::move(endpoint), limits.max_client_message), options);
  p.client->open(f.name);
  return p;
}

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

}  // namespace pms::test
