// A real cache in the loop (issue 19, requirement 6): Debian's nginx on loopback with the repo's
// deploy/nginx/pmstream-cache.conf in front of `pmstream serve --http-port`, and receiver-driven clients
// (`pmstream stream --mode receiver`) flying bunny through it. A second client on the same path is served
// by the cache alone; ten clients on overlapping stretches of one orbit report the hit rate of each fetch
// policy (docs/protocol.md, "Receiver-driven client").
#include <gtest/gtest.h>
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "apps/camera_json.h"
#include "bench/loopback_daemon.h"
#include "bench/nginx_child.h"
#include "bench/serve_child.h"
#include "client/http_connection.h"
#include "common/error.h"
#include "test_support.h"

namespace pms {
namespace {

namespace fs = std::filesystem;
using bench::NginxChild;
using bench::ServeChild;

// The shipped configuration, as an operator with one origin fills it in.
const fs::path kConfig = fs::path(PMSTREAM_SOURCE_DIR) / "deploy/nginx/pmstream-cache.conf";

struct Flight {
  nlohmann::json report;  // `pmstream stream --json`
  std::string mesh;       // the PLY it saved, byte for byte
  uint64_t rounds = 0;    // adapt -> request -> attach cycles, over all frames
};

Flight fly(const std::string& server, const fs::path& path, const std::string& fetch_flags, const fs::path& dir,
           const std::string& name) {
  const fs::path mesh = dir / (name + ".ply");
  const test::CliRun run =
      test::run_pmstream("stream --mode receiver --server " + server + " --model bunny --path " + path.string() + " " +
                         fetch_flags + " --save-mesh " + mesh.string() + " --json");
  if (run.exit_code != 0) fail("pmstream stream", run.err);
  Flight flight{nlohmann::json::parse(run.out), bench::file_text(mesh)};
  for (const nlohmann::json& frame : flight.report["frames"]) flight.rounds += frame["rounds"].get<uint64_t>();
  return flight;
}

uint64_t origin_split_requests(ServeChild& origin) { return origin.stats().line["http"]["split_requests"]; }
uint64_t origin_requests(ServeChild& origin) { return origin.stats().line["http"]["requests"]; }

// The origin behind the cache. The cache is one address with many connections: trusted, it is not capped
// as one client would be, and each viewer behind it is charged its own budget (the configuration sends
// X-Forwarded-For).
std::vector<std::string> origin_flags(const fs::path& model) {
  return {model.string(), "--http-port", "0", "--trusted-proxy", "127.0.0.1"};
}

class NginxCache : public ::testing::Test {
 protected:
  void SetUp() override {
    nginx_ = bench::find_daemon("nginx");
    if (nginx_.empty()) GTEST_SKIP() << "nginx is not installed (scripts/setup.sh installs Debian's nginx-light)";
    const fs::path model = test::shared_model("bunny.ply.xz");
    if (model.empty()) GTEST_SKIP() << "../shared/models/bunny.ply.xz not found: this test needs the shared meshes";
    dir_ = test::temp_dir();
    pms_ = dir_ / "bunny.pms";
    const test::CliRun build = test::run_pmstream("build " + model.string() + " -o " + pms_.string());
    ASSERT_EQ(build.exit_code, 0) << build.err;
    origin_ = std::make_unique<ServeChild>(PMSTREAM_BINARY, origin_flags(pms_));
    origin_port_ = origin_->listening()["http_port"].get<uint16_t>();
  }

  fs::path make_path(const std::string& kind, uint32_t frames) {
    const fs::path path = dir_ / (kind + std::to_string(frames) + ".json");
    const test::CliRun run = test::run_pmstream("path " + kind + " --model " + pms_.string() + " --frames " +
                                                std::to_string(frames) + " -o " + path.string());
    if (run.exit_code != 0) fail("pmstream path", run.err);
    return path;
  }

  std::string nginx_;
  fs::path dir_, pms_;
  std::unique_ptr<ServeChild> origin_;
  uint16_t origin_port_ = 0;
};

TEST_F(NginxCache, ASecondClientOnTheSamePathIsServedFromTheCacheAlone) {
  const fs::path path = make_path("zoom", 20);
  for (const std::string fetch : {"lists", "blocks"}) {
    SCOPED_TRACE("--fetch " + fetch);
    NginxChild nginx(nginx_, kConfig, test::temp_dir(), {origin_port_});  // an empty cache
    const Flight first = fly(nginx.url(), path, "--fetch " + fetch, dir_, fetch + "_first");
    const uint64_t split_requests = first.report["split_requests"];
    ASSERT_GT(split_requests, 0u);
    EXPECT_EQ(first.report["cache_hits"], 0u) << "a lone client never asks for a URL twice";
    const uint64_t origin_splits = origin_split_requests(*origin_), origin_all = origin_requests(*origin_);

    const Flight second = fly(nginx.url(), path, "--fetch " + fetch, dir_, fetch + "_second");
    EXPECT_EQ(second.report["split_requests"], split_requests) << "the same path asks for the same URLs";
    EXPECT_EQ(second.report["cache_hits"], split_requests) << "every split answer says X-Cache-Status: HIT";
    EXPECT_EQ(origin_split_requests(*origin_), origin_splits) << "the origin saw no split request from it";
    EXPECT_EQ(origin_requests(*origin_), origin_all) << "nor any other: the catalogue and base are cached too";
    EXPECT_EQ(second.report["total_down_payload_bytes"], first.report["total_down_payload_bytes"]);
    EXPECT_EQ(second.report["vsplits_received"], first.report["vsplits_received"]);
    ASSERT_FALSE(first.mesh.empty());
    EXPECT_TRUE(second.mesh == first.mesh) << "the meshes differ";
  }
}

// Ten viewers on overlapping stretches of one orbit (client i flies frames 10i .. 10i + 19 of 100, so
// neighbours share half their path), one after another through one cache, for each fetch policy.
TEST_F(NginxCache, TenClientsOnDifferentPathsShareTheCache) {
  const std::vector<Camera> orbit = app::load_path(make_path("orbit", 100).string());
  std::vector<fs::path> paths;
  // A sanitizer build checks the same invariants with fewer flights (each a pmstream process under ASan).
  const size_t clients = test::kSanitized ? 4 : 10;
  for (size_t i = 0; i < clients; ++i) {
    std::vector<Camera> stretch;
    for (size_t k = 0; k < 20; ++k) stretch.push_back(orbit[(10 * i + k) % orbit.size()]);
    paths.push_back(dir_ / ("stretch" + std::to_string(i) + ".json"));
    app::save_path(paths.back().string(), stretch);
  }
  for (const std::string fetch : {"--fetch lists", "--fetch blocks", "--fetch blocks --block-depth 3"}) {
    SCOPED_TRACE(fetch);
    NginxChild nginx(nginx_, kConfig, test::temp_dir(), {origin_port_});
    const nlohmann::json origin_before = origin_->stats().line["http"];
    uint64_t requests = 0, hits = 0, down = 0, payload = 0, up = 0, rounds = 0, splits = 0;
    for (size_t i = 0; i < paths.size(); ++i) {
      const Flight flight = fly(nginx.url(), paths[i], fetch, dir_, "ten" + std::to_string(i));
      requests += flight.report["split_requests"].get<uint64_t>();
      hits += flight.report["cache_hits"].get<uint64_t>();
      down += flight.report["total_down_bytes"].get<uint64_t>();
      payload += flight.report["total_down_payload_bytes"].get<uint64_t>();
      up += flight.report["total_up_bytes"].get<uint64_t>();
      splits += flight.report["vsplits_received"].get<uint64_t>();
      rounds += flight.rounds;
    }
    const nlohmann::json origin_after = origin_->stats().line["http"];
    const auto origin = [&](const char* counter) {
      return origin_after[counter].get<uint64_t>() - origin_before[counter].get<uint64_t>();
    };
    EXPECT_EQ(origin("split_requests"), requests - hits) << "each answer not from the cache is one origin request";
    std::printf(
        "nginx, %zu clients, bunny orbit stretches, %s: %llu split GETs, %llu HIT (hit rate %.1f %%); "
        "origin: %llu split requests, %llu splits, %llu B out; per client: %.0f splits, %.0f B down "
        "(%.0f payload), %.0f B up, %.1f GETs, %.1f rounds\n",
        clients, fetch.c_str(), (unsigned long long)requests, (unsigned long long)hits,
        100.0 * double(hits) / double(std::max<uint64_t>(requests, 1)), (unsigned long long)origin("split_requests"),
        (unsigned long long)origin("splits_served"), (unsigned long long)origin("bytes_out"),
        double(splits) / double(clients), double(down) / double(clients), double(payload) / double(clients),
        double(up) / double(clients), double(requests) / double(clients), double(rounds) / double(clients));
    std::fflush(stdout);
  }
}

// The multilevel mode's levels are immutable resources too: a second viewer behind the cache loads every
// level without the origin seeing a request, and ends on the same mesh.
TEST_F(NginxCache, MultilevelLevelsComeFromTheCacheTheSecondTime) {
  const fs::path pml = dir_ / "bunnyml.pml";
  const test::CliRun build = test::run_pmstream("multilevel build " + test::shared_model("bunny.ply.xz").string() +
                                                " -o " + pml.string() + " --levels 8");
  ASSERT_EQ(build.exit_code, 0) << build.err;
  ServeChild origin(PMSTREAM_BINARY, origin_flags(pml));
  NginxChild nginx(nginx_, kConfig, test::temp_dir(), {origin.listening()["http_port"].get<uint16_t>()});
  const fs::path path = make_path("zoom", 10);
  const auto fly_levels = [&](const std::string& name) {
    const fs::path mesh = dir_ / (name + ".ply");
    const test::CliRun run =
        test::run_pmstream("stream --mode multilevel --server " + nginx.url() + " --model bunnyml --path " +
                           path.string() + " --save-mesh " + mesh.string() + " --json");
    if (run.exit_code != 0) fail("pmstream stream", run.err);
    return Flight{nlohmann::json::parse(run.out), bench::file_text(mesh)};
  };
  const Flight first = fly_levels("ml_first");
  ASSERT_EQ(first.report["levels_received"], 8u);
  const uint64_t origin_all = origin_requests(origin);
  const Flight second = fly_levels("ml_second");
  EXPECT_EQ(second.report["levels_received"], 8u);
  EXPECT_EQ(origin_requests(origin), origin_all) << "the catalogue, the head and every level came from the cache";
  EXPECT_EQ(second.report["total_down_payload_bytes"], first.report["total_down_payload_bytes"]);
  ASSERT_FALSE(first.mesh.empty());
  EXPECT_TRUE(second.mesh == first.mesh) << "the meshes differ";
}

// The catalogue behind the cache (docs/protocol.md, "Versions"): stored for its max-age, then revalidated
// (the origin answers 304 while the model set is unchanged); a model added to the origin and reloaded
// (SIGHUP) reaches a client behind the cache within the max-age, and streams through it.
TEST_F(NginxCache, AModelAddedToTheOriginReachesClientsBehindTheCacheWithinTheCataloguesMaxAge) {
  using Clock = std::chrono::steady_clock;
  const fs::path models = dir_ / "models", added = dir_ / "terrain.pms";
  fs::create_directories(models);
  fs::copy_file(pms_, models / "bunny.pms");
  ASSERT_EQ(test::run_pmstream("build terrain:20000 -o " + added.string()).exit_code, 0);
  constexpr int kMaxAge = 2;
  std::vector<std::string> flags = origin_flags(models);
  flags.insert(flags.end(), {"--catalogue-max-age", std::to_string(kMaxAge)});
  ServeChild origin(PMSTREAM_BINARY, flags);
  NginxChild nginx(nginx_, kConfig, test::temp_dir(), {origin.listening()["http_port"].get<uint16_t>()});
  client::HttpConnection http(client::parse_http_url(nginx.url()));
  const auto catalogue = [&http] {
    const client::HttpAnswer answer = http.get("/models");
    EXPECT_EQ(answer.status, 200);
    return std::pair(std::string(answer.body.begin(), answer.body.end()), answer.cache_status);
  };
  const auto lists_terrain = [](const std::string& text) { return text.find("\"terrain\"") != std::string::npos; };

  const auto stored = Clock::now();
  EXPECT_EQ(catalogue().second, "MISS");
  EXPECT_EQ(catalogue().second, "HIT");
  fs::copy_file(added, models / "terrain.pms");
  EXPECT_EQ(origin.reload()["added"], nlohmann::json::array({"terrain"}));
  const auto [cached, cached_status] = catalogue();
  if (Clock::now() - stored < std::chrono::seconds(kMaxAge)) {  // within the max-age: the entry stored
    EXPECT_EQ(cached_status, "HIT");
    EXPECT_FALSE(lists_terrain(cached));
  }
  // nginx keeps time in whole seconds: an entry is stale after max-age and before max-age + 1 s.
  const auto past_max_age = std::chrono::milliseconds(kMaxAge * 1000 + 1100);
  std::this_thread::sleep_until(stored + past_max_age);
  const auto [fresh, fresh_status] = catalogue();
  EXPECT_TRUE(lists_terrain(fresh)) << "past the max-age the cache asks again and gets the new list";
  EXPECT_EQ(fresh_status, "EXPIRED");
  const uint64_t not_modified = origin.stats().line["http"]["not_modified"];
  std::this_thread::sleep_for(past_max_age);
  EXPECT_EQ(catalogue().second, "REVALIDATED") << "unchanged: the origin's 304 renews the stored list";
  EXPECT_EQ(origin.stats().line["http"]["not_modified"], not_modified + 1);

  const fs::path path = dir_ / "terrain_orbit.json";
  ASSERT_EQ(test::run_pmstream("path orbit --model " + added.string() + " --frames 6 -o " + path.string()).exit_code, 0);
  const test::CliRun run = test::run_pmstream("stream --mode receiver --server " + nginx.url() +
                                              " --model terrain --path " + path.string() + " --json");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_GT(nlohmann::json::parse(run.out)["vsplits_received"].get<uint64_t>(), 0u);
}

}  // namespace
}  // namespace pms
