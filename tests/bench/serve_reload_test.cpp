// SIGHUP on a real `pmstream serve` (issue 45; docs/operating.md, "Signals") while clients stream: a TCP
// session of a model the reload removes flies on to the end of its path, a model added shows in GET /models
// and LIST, a corrupt file is skipped with a log line, and a file replaced under its name is a new version
// whose old URLs answer 410 while a receiver-driven client re-opens on the new one.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "apps/camera_path.h"
#include "bench/serve_child.h"
#include "client/http_connection.h"
#include "client/receiver_client.h"
#include "client/streaming_client.h"
#include "spm/pms_file.h"
#include "test_support.h"

namespace pms::bench {
namespace {

namespace fs = std::filesystem;

void build_terrain(const fs::path& pms, int faces) {
  const test::CliRun build = test::run_pmstream("build terrain:" + std::to_string(faces) + " -o " + pms.string());
  ASSERT_EQ(build.exit_code, 0) << build.err;
}

std::vector<Camera> orbit_of(const fs::path& pms, uint32_t frames) {
  app::PathOptions options;
  options.frames = frames;
  return app::make_camera_path(app::PathKind::orbit, PmsFile::open(pms.string())->model(), options);
}

// The mesh a lock-step client ends a path with, as the ids of its vertices: one front, one mesh.
std::vector<VertexId> fly(client::StreamingClient& client, const std::vector<Camera>& path) {
  for (const Camera& camera : path) client.frame(camera);
  std::vector<VertexId> ids = client.session().mesh_vertices();
  std::sort(ids.begin(), ids.end(), [](VertexId x, VertexId y) { return std::pair(x.tree, x.node) < std::pair(y.tree, y.node); });
  return ids;
}

nlohmann::json models_of(uint16_t http_port) {
  client::HttpConnection http(client::HttpUrl{"127.0.0.1", http_port, ""});
  const client::HttpAnswer answer = http.get("/models");
  EXPECT_EQ(answer.status, 200);
  const nlohmann::json catalogue = nlohmann::json::parse(answer.body.begin(), answer.body.end());
  nlohmann::json by_name = nlohmann::json::object();
  for (const nlohmann::json& entry : catalogue["models"])
    by_name[entry["name"].get<std::string>()] = entry["version"];
  return by_name;
}

TEST(ServeReload, SighupWhileClientsStream) {
  const fs::path dir = test::temp_dir(), models = dir / "models";
  fs::create_directories(models);
  build_terrain(models / "a.pms", 20000);
  build_terrain(models / "b.pms", 20000);
  build_terrain(dir / "b2.pms", 30000);  // b's replacement: another model under the same name
  build_terrain(dir / "c.pms", 10000);
  ServeChild server(PMSTREAM_BINARY, {models.string(), "--http-port", "0", "--catalogue-max-age", "0"});
  const uint16_t http_port = server.listening()["http_port"];
  const std::vector<Camera> path_a = orbit_of(models / "a.pms", 12), path_b = orbit_of(dir / "b2.pms", 12);
  const nlohmann::json before = models_of(http_port);
  ASSERT_EQ(before.size(), 2u);

  client::StreamingClient undisturbed("127.0.0.1", server.port(), client::ClientOptions{1.0f});
  undisturbed.open("a");
  const std::vector<VertexId> want_a = fly(undisturbed, path_a);

  // A session of `a` flies lap after lap until the reload is done, then one more: a reload in the middle
  // of its frames, whatever the timing.
  std::atomic<bool> reloaded{false};
  std::atomic<int> laps{0};
  std::vector<VertexId> got_a;
  std::string tcp_error;
  std::thread tcp_flight([&] {
    try {
      client::StreamingClient client("127.0.0.1", server.port(), client::ClientOptions{1.0f});
      client.open("a");
      while (!reloaded.load()) {
        fly(client, path_a);
        ++laps;
      }
      got_a = fly(client, path_a);
    } catch (const std::exception& e) {
      tcp_error = e.what();
    }
  });
  client::ReceiverClient receiver(client::HttpUrl{"127.0.0.1", http_port, ""});
  receiver.open("b");
  for (size_t i = 0; i < 4; ++i) receiver.frame(orbit_of(models / "b.pms", 12)[i]);

  for (int i = 0; i < 3000 && laps.load() == 0; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  EXPECT_GT(laps.load(), 0) << "the session flies: the reload comes in the middle of its laps";
  fs::remove(models / "a.pms");
  fs::copy_file(dir / "c.pms", models / "c.pms");
  fs::copy_file(dir / "b2.pms", models / "b.pms.new");
  fs::rename(models / "b.pms.new", models / "b.pms");
  {
    std::ifstream whole(dir / "c.pms", std::ios::binary);
    std::string bytes(std::istreambuf_iterator<char>(whole), {});
    std::ofstream(models / "bad.pms", std::ios::binary) << bytes.substr(0, bytes.size() / 2);  // truncated
  }
  const nlohmann::json line = server.reload();
  reloaded = true;
  EXPECT_EQ(line["added"], nlohmann::json::array({"c"}));
  EXPECT_EQ(line["removed"], nlohmann::json::array({"a"}));
  EXPECT_EQ(line["replaced"], nlohmann::json::array({"b"}));
  ASSERT_EQ(line["skipped"].size(), 1u);
  EXPECT_NE(line["skipped"][0].get<std::string>().find("bad.pms"), std::string::npos) << line;

  const nlohmann::json after = models_of(http_port);
  EXPECT_FALSE(after.contains("a"));
  EXPECT_TRUE(after.contains("c"));
  EXPECT_NE(after["b"], before["b"]) << "a changed file under the same name is a new version";
  client::StreamingClient lister("127.0.0.1", server.port(), client::ClientOptions{1.0f});
  std::vector<std::string> listed;
  for (const protocol::ModelInfo& info : lister.list().models) listed.push_back(info.name);
  std::sort(listed.begin(), listed.end());
  EXPECT_EQ(listed, (std::vector<std::string>{"b", "c"}));
  client::HttpConnection http(client::HttpUrl{"127.0.0.1", http_port, ""});
  EXPECT_EQ(http.get("/models/b/" + before["b"].get<std::string>() + "/base").status, 410);
  EXPECT_EQ(http.get("/models/a/" + before["a"].get<std::string>() + "/base").status, 404);

  for (const Camera& camera : path_b) receiver.frame(camera);
  EXPECT_EQ(receiver.reopens(), 1u);
  EXPECT_EQ(receiver.version(), after["b"]);

  tcp_flight.join();
  EXPECT_EQ(tcp_error, "");
  EXPECT_EQ(got_a, want_a) << "the session of the removed model ends its flight on the model it opened";

  const ServeStats stopped = server.stop();
  EXPECT_EQ(stopped.line["reloads"], 1);
  EXPECT_EQ(stopped.line["models_added"], 1);
  EXPECT_EQ(stopped.line["models_removed"], 1);
  EXPECT_EQ(stopped.line["models_replaced"], 1);
  EXPECT_EQ(stopped.line["files_skipped"], 1);
  EXPECT_EQ(stopped.sessions_failed, 0u);
  EXPECT_NE(server.log().find("reload: skipped"), std::string::npos) << server.log();
  EXPECT_NE(server.log().find("bad.pms"), std::string::npos) << server.log();
}

}  // namespace
}  // namespace pms::bench
