// Receiver-driven viewers behind the nginx cache tier (issue 45, requirement 4): Debian's nginx on loopback
// with the repo's deploy/nginx/pmstream-cache.conf in front of two `pmstream serve` origins, and native
// receiver-driven clients (blocks and per-split lists) flying bunny on a few paths, several viewers a path,
// each from a loopback address of its own. Mid-flight one origin is killed (SIGKILL): nginx sends what it
// asked of it to the other, and every viewer finishes with the mesh local refinement makes for its last
// view. The origins trust nginx's X-Forwarded-For, so their per-address accounting sees the viewers.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "bench/loopback_daemon.h"
#include "bench/nginx_child.h"
#include "bench/serve_child.h"
#include "bench/tier_flight.h"
#include "streaming_fixture.h"
#include "test_support.h"

namespace pms {
namespace {

namespace fs = std::filesystem;
using bench::NginxChild;
using bench::ServeChild;
using bench::TierPlan;
using bench::TierViewer;
using namespace std::chrono_literals;

constexpr float kTolerance = 1;
constexpr size_t kPaths = 3, kViewersPerPath = 4, kFrames = 16;

uint64_t http_counter(ServeChild& origin, const char* name) { return origin.stats().line["http"][name]; }

class NginxTier : public ::testing::Test {
 protected:
  void SetUp() override {
    PMS_REQUIRE_SHARED_MODEL(model, "bunny.ply.xz");
    const std::string nginx = bench::find_daemon("nginx");
    if (nginx.empty()) GTEST_SKIP() << "nginx is not installed (scripts/setup.sh installs Debian's nginx-light)";
    fixture_ = &test::file_fixture(model.string(), "bunny");
    std::vector<uint16_t> ports;
    for (size_t i = 0; i < 2; ++i) {
      // Trusting the tier: each viewer behind it is charged its own budget (docs/operating.md, "HTTP").
      origins_.push_back(std::make_unique<ServeChild>(
          PMSTREAM_BINARY, std::vector<std::string>{fixture_->path, "--http-port", "0", "--trusted-proxy", "127.0.0.1"}));
      ports.push_back(origins_.back()->listening()["http_port"].get<uint16_t>());
    }
    nginx_ = std::make_unique<NginxChild>(nginx, fs::path(PMSTREAM_SOURCE_DIR) / "deploy/nginx/pmstream-cache.conf",
                                          test::temp_dir(), ports);
  }

  // Viewer i on path i % kPaths, every other one fetching per-split lists, each from 127.0.0.(10 + i); the
  // viewers of a path start one after another, so the later ones find what the first asked for cached.
  TierPlan plan() const {
    TierPlan p;
    p.server = client::parse_http_url(nginx_->url());
    p.model = "bunny";
    p.tolerance = kTolerance;
    for (size_t i = 0; i < kPaths * kViewersPerPath; ++i) {
      bench::TierViewerPlan viewer;
      viewer.path = test::orbit_path(fixture_->hierarchy, kFrames, 1.3f * float(i % kPaths));
      viewer.fetch = i % 2 == 0 ? client::FetchPolicy::blocks : client::FetchPolicy::lists;
      viewer.local_address = "127.0.0." + std::to_string(10 + i);
      viewer.start = std::chrono::milliseconds(150 * (i / kPaths));
      p.viewers.push_back(viewer);
    }
    return p;
  }

  // Flies `p`; every viewer must finish with local refinement's mesh for its last view.
  std::vector<TierViewer> fly(const TierPlan& p) {
    test::LocalMeshCheck meshes(fixture_->snapped, kTolerance);
    const std::vector<TierViewer> viewers = bench::fly_tier(p, [&](size_t i, client::ReceiverClient& client) {
      meshes.check(i, client.session().mesh(), p.viewers[i].path.back());
    });
    for (size_t i = 0; i < viewers.size(); ++i) EXPECT_EQ(viewers[i].error, "") << "viewer " << i << " failed";
    EXPECT_TRUE(meshes.all_same());
    return viewers;
  }

  const test::Fixture* fixture_ = nullptr;
  std::vector<std::unique_ptr<ServeChild>> origins_;
  std::unique_ptr<NginxChild> nginx_;
};

TEST_F(NginxTier, ViewersFlyOnThroughAKilledOriginAndTheOriginsSeeEachViewer) {
  TierPlan p = plan();
  // When the second viewer of the first path is halfway: the first viewers near their end, the last ones
  // starting.
  p.event_viewer = kPaths;
  p.event_frame = kFrames / 2;
  uint64_t killed_origin_splits = 0, survivor_before = 0;
  p.event = [&] {
    killed_origin_splits = http_counter(*origins_[0], "split_requests");
    survivor_before = http_counter(*origins_[1], "split_requests");
    origins_[0].reset();  // SIGKILL
  };
  const std::vector<TierViewer> viewers = fly(p);
  uint64_t split_gets = 0, hits = 0;
  for (const TierViewer& v : viewers) {
    split_gets += v.totals.split_requests;
    hits += v.totals.cache_hits;
  }
  ServeChild& survivor = *origins_[1];
  const uint64_t survivor_after = http_counter(survivor, "split_requests");
  EXPECT_GT(killed_origin_splits, 0u) << "both origins served before the kill (round robin)";
  EXPECT_GT(survivor_before, 0u);
  EXPECT_GT(survivor_after, survivor_before) << "the misses after the kill went to the origin left";
  EXPECT_GT(hits, 0u) << "later viewers of a path were served by the cache";
  // nginx found origin1 dead (a refused connect, a reset) and sent those requests on to origin2; no viewer
  // got an error.
  size_t failed_over = 0, errors = 0;
  for (const bench::AccessLogLine& line : bench::read_access_log(nginx_->access_log())) {
    failed_over += line.upstreams.find(',') != std::string::npos;
    errors += line.status != 200;
  }
  std::printf("nginx tier: %zu viewers, %llu split GETs, %llu HIT; origin1 answered %llu before its kill, origin2 "
              "%llu before and %llu after; nginx sent %zu requests on to origin2 after origin1 failed\n",
              viewers.size(), (unsigned long long)split_gets, (unsigned long long)hits,
              (unsigned long long)killed_origin_splits, (unsigned long long)survivor_before,
              (unsigned long long)(survivor_after - survivor_before), failed_over);
  std::fflush(stdout);
  EXPECT_GT(failed_over, 0u);
  EXPECT_EQ(errors, 0u);

  // The origin left tracks nginx's address (its connections) and each viewer that it answered a miss for,
  // never more; a viewer from a new address asking for what nobody asked (per-split lists on a path of its
  // own) adds exactly its address: what the origin charges is the viewer, not nginx.
  const uint64_t tracked = http_counter(survivor, "addresses_tracked");
  EXPECT_GE(tracked, 2u);
  EXPECT_LE(tracked, 1 + viewers.size());
  TierPlan late;
  late.server = p.server;
  late.model = p.model;
  late.tolerance = kTolerance;
  late.viewers.push_back({test::orbit_path(fixture_->hierarchy, 4, 0.6f), client::FetchPolicy::lists, "127.0.0.250"});
  EXPECT_GT(fly(late).at(0).totals.split_requests, 0u);
  EXPECT_EQ(http_counter(survivor, "addresses_tracked"), tracked + 1);
  const bench::ServeStats stopped = survivor.stop();
  EXPECT_EQ(stopped.protocol_errors + stopped.sessions_failed, 0u) << survivor.log();
}

}  // namespace
}  // namespace pms
