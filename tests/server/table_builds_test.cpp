// Tables built when a mode first needs them (server/model_tables.h, table_builds.h): a cold OPEN gets what
// a preloaded server sends, each table is built once whatever asks at once, the build cap holds under many
// opens, and a .pms model's derived levels are those `pmstream multilevel build` makes.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <string>
#include <thread>
#include <vector>

#include "builder/build.h"
#include "client/multilevel_client.h"
#include "client/streaming_client.h"
#include "io/shapes.h"
#include "multilevel/build.h"
#include "protocol/client_messages.h"
#include "protocol/message_types.h"
#include "server/catalogue.h"
#include "server/http_server.h"
#include "server/tcp_server.h"
#include "spm/pms_file.h"
#include "streaming_fixture.h"
#include "test_support.h"

namespace pms {
namespace {

using server::Catalogue;
using server::ServedMode;
using server::TableOptions;

const test::Fixture& sphere() {
  static const test::Fixture f = test::make_fixture(make_sphere(30, 40), "ball");
  return f;
}

TableOptions cold(uint32_t max_builds = 2) {
  TableOptions options;
  options.preload.reset();
  options.max_builds = max_builds;
  return options;
}

struct Flight {
  uint64_t bytes_down = 0;
  test::Faces faces;
};

// A client of `mode` flying a few frames of an orbit: the bytes it received and the mesh it ends with.
Flight fly(const std::shared_ptr<const Catalogue>& catalogue, protocol::StreamMode mode) {
  server::TcpServer tcp(catalogue, server::ServerLimits{}, "127.0.0.1", 0);
  tcp.start();
  client::ClientOptions options;
  options.mode = mode;
  client::StreamingClient client("127.0.0.1", tcp.port(), options);
  client.open("ball");
  for (const Camera& camera : test::orbit_path(sphere().hierarchy, 4, 0.3f)) client.frame(camera);
  Flight out;
  out.bytes_down = client.counters().bytes_down;
  out.faces = test::faces_by_id(client.session().mesh());
  return out;
}

TEST(Tables, AColdOpenGetsWhatAPreloadedServerSends) {
  const auto preloaded = Catalogue::open({sphere().path}, protocol::kDefaultPositionBits);
  for (const protocol::StreamMode mode : {protocol::StreamMode::sender_driven, protocol::StreamMode::sender_plain,
                                          protocol::StreamMode::view_independent, protocol::StreamMode::dag}) {
    SCOPED_TRACE(protocol::mode_name(mode));
    const auto lazy = Catalogue::open({sphere().path}, protocol::kDefaultPositionBits, cold());
    const ServedMode served = server::served_mode_of(mode);
    EXPECT_FALSE(lazy->find("ball")->tables->ready(served));
    const Flight want = fly(preloaded, mode);
    const Flight got = fly(lazy, mode);
    EXPECT_TRUE(lazy->find("ball")->tables->ready(served));
    EXPECT_EQ(got.bytes_down, want.bytes_down);
    EXPECT_EQ(got.faces, want.faces);
    EXPECT_GT(lazy->find("ball")->tables->bytes(served), 0u);
  }
}

TEST(Tables, BuiltOnceUnderConcurrentFirstOpens) {
  const auto catalogue = Catalogue::open({sphere().path}, protocol::kDefaultPositionBits, cold(4));
  server::TcpServer tcp(catalogue, server::ServerLimits{}, "127.0.0.1", 0);
  tcp.start();
  std::atomic<int> opened{0};
  std::vector<std::thread> clients;
  for (int i = 0; i < 8; ++i)
    clients.emplace_back([&] {
      client::StreamingClient client("127.0.0.1", tcp.port(), client::ClientOptions{});
      client.open("ball");
      ++opened;
    });
  for (std::thread& t : clients) t.join();
  EXPECT_EQ(opened.load(), 8);
  EXPECT_EQ(catalogue->table_builds().stats().started.load(), 1u) << "one build of the sender tables";
  EXPECT_GE(catalogue->table_builds().stats().waits.load(), 1u);
}

// Many sessions open every TCP mode of several models at once, each with a handshake deadline; with one
// build allowed at a time, no two run together, every session gets BASE or an ERROR, and a good client
// opened afterwards streams.
TEST(Tables, TheBuildCapHoldsUnderManyOpensOfEveryMode) {
  std::vector<std::string> paths;
  for (const char* name : {"m0", "m1", "m2"}) paths.push_back(test::make_fixture(make_sphere(24, 32), name).path);
  const auto catalogue = Catalogue::open(paths, protocol::kDefaultPositionBits, cold(1));
  server::ServerLimits limits;
  limits.handshake_timeout_ms = 20000;
  server::TcpServer tcp(catalogue, limits, "127.0.0.1", 0);
  tcp.start();
  std::atomic<int> answered{0}, failed{0};
  std::vector<std::thread> peers;
  for (int round = 0; round < 2; ++round)
    for (const char* model : {"m0", "m1", "m2"})
      for (const protocol::StreamMode mode : {protocol::StreamMode::sender_driven, protocol::StreamMode::sender_plain,
                                              protocol::StreamMode::view_independent, protocol::StreamMode::dag})
        peers.emplace_back([&, model, mode] {
          try {
            client::ClientOptions options;
            options.mode = mode;
            client::StreamingClient client("127.0.0.1", tcp.port(), options);
            client.open(model);
            ++answered;
          } catch (const std::exception&) {
            ++failed;
          }
        });
  for (std::thread& t : peers) t.join();
  EXPECT_EQ(answered.load() + failed.load(), 24);
  EXPECT_EQ(failed.load(), 0);
  const server::TableBuildStats& stats = catalogue->table_builds().stats();
  EXPECT_EQ(stats.peak_running.load(), 1u);
  EXPECT_EQ(stats.started.load(), 12u) << "each model's mode once";
  client::StreamingClient good("127.0.0.1", tcp.port(), client::ClientOptions{});
  good.open("m1");
  EXPECT_NO_THROW(good.frame(test::orbit_path(sphere().hierarchy, 1, 0)[0]));
}

// Per level (0 finest), its own triangles as position triples, each rotated to start at its smallest
// corner (orientation kept), sorted: equal for two multilevel meshes of the same levels in any order.
using Corner = std::array<float, 3>;
std::vector<std::vector<std::array<Corner, 3>>> triangles_by_level(const MultilevelMesh& m) {
  std::vector<std::vector<std::array<Corner, 3>>> levels(m.level_count());
  for (uint32_t l = 0; l < m.level_count(); ++l) {
    const uint32_t begin = l + 1 < m.level_count() ? m.triangle_count[l + 1] : 0, end = m.triangle_count[l];
    for (uint32_t t = begin; t < end; ++t) {
      std::array<Corner, 3> tri;
      for (int k = 0; k < 3; ++k) {
        const uint32_t v = m.triangles[3 * size_t(t) + k];
        tri[k] = {m.positions[3 * size_t(v)], m.positions[3 * size_t(v) + 1], m.positions[3 * size_t(v) + 2]};
      }
      std::rotate(tri.begin(), std::min_element(tri.begin(), tri.end()), tri.end());
      levels[l].push_back(tri);
    }
    std::sort(levels[l].begin(), levels[l].end());
  }
  return levels;
}

TEST(Tables, APmsOverTheMultilevelRoutesGivesTheLevelsOfMultilevelBuild) {
  const Mesh mesh = make_sphere(30, 40);
  const BuildResult built = build_progressive_mesh(mesh);
  const MultilevelMesh want = build_multilevel(mesh, collapses_of(built.hierarchy));
  const auto catalogue = Catalogue::open({sphere().path}, protocol::kDefaultPositionBits, cold());
  server::HttpServer http(catalogue, server::HttpLimits{}, "127.0.0.1", 0);
  http.start();
  client::MultilevelOptions options;
  options.budget = uint64_t(1) << 40;  // every level
  options.compressed = false;          // the binary form: positions as built
  client::MultilevelClient client(client::HttpUrl{"127.0.0.1", http.port(), ""}, options);
  client.open("ball");
  Camera far;
  far.eye[2] = 1000;
  client.frame(far);
  const MultilevelMesh& got = client.mesh();
  EXPECT_TRUE(catalogue->find("ball")->tables->ready(ServedMode::multilevel));
  EXPECT_EQ(got.vertex_count, want.vertex_count);
  EXPECT_EQ(got.triangle_count, want.triangle_count);
  EXPECT_EQ(triangles_by_level(got), triangles_by_level(want));
}

}  // namespace
}  // namespace pms
