// What the server tests share: a model built and written as a .pms file, camera paths over it, and the mesh
// a client should end with (local refinement of the same view, on the positions the wire carries).
#pragma once
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "client/http_connection.h"
#include "client/streaming_client.h"
#include "common/camera.h"
#include "io/mesh.h"
#include "protocol/message_types.h"
#include "protocol/server_messages.h"
#include "render/render.h"
#include "server/catalogue.h"
#include "server/http_server.h"
#include "server/limits.h"
#include "server/session.h"
#include "server/tcp_server.h"
#include "spm/hierarchy.h"
#include "spm/selective_mesh.h"
#include "spm/vertex_id.h"

namespace pms::test {

using Faces = std::vector<std::array<VertexId, 3>>;

struct Fixture {
  Hierarchy hierarchy;  // as built
  Hierarchy snapped;    // positions and normals as clients receive them
  std::string path;     // the .pms file served
  std::shared_ptr<const server::Catalogue> catalogue;
  std::string name;
};

// Where the resources of the version `catalogue` serves of model `name` are: /models/NAME/VERSION.
std::string model_url(const server::Catalogue& catalogue, const std::string& name);

// Builds `mesh` and writes it to NAME.pms in a fresh temp_dir().
Fixture make_fixture(const Mesh& mesh, const std::string& name);

// make_terrain(faces, seed) built, written and served as "terrain", once per test program and size: the test
// files that fly over the same terrain share one build.
const Fixture& terrain_fixture(uint64_t faces, uint32_t seed);

// A terrain with smooth per-vertex normals and colors, so both travel in the split records; made once.
const Fixture& attributed_terrain();

// A mesh file (a shared model), cleaned, built and written as NAME.pms, once per test program and file.
const Fixture& file_fixture(const std::string& mesh_path, const std::string& name);

// The servers a test runs on a free loopback port: started when made, stopped when destroyed.
struct LoopbackTcpServer {
  explicit LoopbackTcpServer(std::shared_ptr<const server::Catalogue> catalogue, server::ServerLimits limits = {},
                             uint16_t port = 0)
      : tcp(std::move(catalogue), limits, "127.0.0.1", port) {
    tcp.start();
  }
  uint16_t port() const { return tcp.port(); }
  server::TcpServer tcp;
};

struct LoopbackHttpServer {
  explicit LoopbackHttpServer(std::shared_ptr<const server::Catalogue> catalogue, const server::HttpLimits& limits = {},
                              const server::WebOptions& web = {})
      : http(std::move(catalogue), limits, "127.0.0.1", 0, web) {
    http.start();
  }
  uint16_t port() const { return http.port(); }
  client::HttpUrl url() const { return client::HttpUrl{"127.0.0.1", http.port(), ""}; }
  server::HttpServer http;
};

// Frames circling the model and closing in on it, so later frames need detail earlier ones did not.
std::vector<Camera> orbit_path(const Hierarchy& h, int frames, float phase);

// The mesh's faces as vertex ids, each rotated to start at its smallest id, sorted: equal iff the same
// front and the same faces with the same orientation.
Faces faces_by_id(SelectiveMesh& mesh);

// The mesh's active vertices by id, with the values a client renders: position, normal, color (zeros
// for what the model lacks).
struct VertexValues {
  VertexId id;
  float position[3] = {0, 0, 0};
  float normal[3] = {0, 0, 0};
  uint8_t color[4] = {0, 0, 0, 0};
  friend bool operator==(const VertexValues&, const VertexValues&) = default;
};
using Vertices = std::vector<VertexValues>;
Vertices vertices_by_id(SelectiveMesh& mesh);

// Local refinement of the same model (positions and normals as the wire carries them) for one view.
Faces local_faces(const Hierarchy& snapped, const Camera& camera, float tolerance);
Vertices local_vertices(const Hierarchy& snapped, const Camera& camera, float tolerance);
// The shaded picture of `mesh` as `camera` sees it (the view from the model's box, as every client frames
// it), and that of local refinement's mesh for the view and τ: what a client judged by PSNR is compared to.
Image picture(const SelectiveMesh& mesh, const Camera& camera, const Hierarchy& model);
Image local_picture(const Hierarchy& snapped, const Camera& camera, float tolerance);

// Viewers flown on threads of their own, each checked as it finishes (from its thread) against local
// refinement for its last view; the test then asserts all_same().
class LocalMeshCheck {
 public:
  LocalMeshCheck(const Hierarchy& snapped, float tolerance) : snapped_(snapped), tolerance_(tolerance) {}
  void check(size_t viewer, SelectiveMesh& mesh, const Camera& last);
  // A gtest assertion result naming how many differ and the first.
  ::testing::AssertionResult all_same() const;

 private:
  const Hierarchy& snapped_;
  float tolerance_;
  mutable std::mutex mutex_;
  std::vector<size_t> differ_;
};

// A client bound to a server Session in this process (LocalTransport), so a test reads the session frame
// by frame; the model is open. `limits` must outlive it.
struct InProcess {
  std::shared_ptr<server::Session> session;
  std::unique_ptr<client::StreamingClient> client;
};
InProcess in_process(const Fixture& f, const client::ClientOptions& options, const server::ServerLimits& limits);

// A raw connection to 127.0.0.1:port that sends `messages` and reads until the server closes; the code of
// the ERROR it got, if any.
std::optional<protocol::ErrorCode> send_raw(uint16_t port, const std::vector<std::vector<uint8_t>>& messages);

}  // namespace pms::test
