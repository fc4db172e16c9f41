// The area-ranking receiver client (cheng-ooi 2008 §4.2, client/receiver_client.h, Ranking::area) against
// the HTTP server over real loopback: it reads the plain records only, its stop rule ends the fetching (a
// view it has settled sends no more GETs), every split it holds is made on a valid mesh, and its picture
// of a real model is close to local refinement's at τ = 1 px by PSNR (its mesh is not meant to equal it).
#include <utility>  // before asio with C++20 (docs/architecture.md, "Stack")

#include <gtest/gtest.h>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <string>

#include "client/receiver_client.h"
#include "common/error.h"
#include "render/render.h"
#include "streaming_fixture.h"
#include "test_support.h"

namespace pms {
namespace {

using test::Fixture;
using Server = test::LoopbackHttpServer;

client::ReceiverOptions area_options(uint32_t stop_area) {
  client::ReceiverOptions options;
  options.ranking = client::Ranking::area;
  options.stop_area = stop_area;
  return options;
}

TEST(ReceiverArea, TheStopRuleEndsTheFetchingAndEverySplitHeldIsMade) {
  const Fixture& f = test::terrain_fixture(30000, 5);
  Server server(f.catalogue);
  client::ReceiverClient client(server.url(), area_options(16));
  client.open("terrain");
  const std::vector<Camera> path = test::orbit_path(f.hierarchy, 6, 0.3f);
  for (const Camera& camera : path) {
    const client::ReceiverFrame r = client.frame(camera);
    EXPECT_TRUE(r.satisfied);  // no budget: each frame runs until its stop rule holds
    EXPECT_EQ(r.queued + r.in_flight, 0u);
  }
  EXPECT_GT(client.session().splits_received(), 0u);
  const uint64_t requests = server.http.stats().requests.load();
  for (int again = 0; again < 3; ++again) {
    const client::ReceiverFrame r = client.frame(path.back());
    EXPECT_EQ(r.split_requests, 0u) << "a settled view asks for nothing more";
  }
  EXPECT_EQ(server.http.stats().requests.load(), requests);
  // Every split held is made (the plain children always refine): the front is the held hierarchy's leaves.
  const VertexHierarchy& h = client.session().hierarchy();
  const SelectiveMesh& mesh = client.session().mesh();
  for (uint32_t slot = 0; slot < h.size(); ++slot)
    EXPECT_EQ(mesh.is_active(slot), h.is_leaf(slot)) << to_string(h.id(slot));
  std::string why;
  EXPECT_TRUE(mesh.check_invariants(&why)) << why;
}

TEST(ReceiverArea, ALargerStopAreaFetchesLess) {
  const Fixture& f = test::terrain_fixture(30000, 5);
  Server server(f.catalogue);
  const Camera camera = test::orbit_path(f.hierarchy, 6, 0.3f).back();
  uint64_t splits[2];
  for (const uint32_t stop : {4u, 64u}) {
    client::ReceiverClient client(server.url(), area_options(stop));
    client.open("terrain");
    client.settle(camera);
    splits[stop == 64u] = client.session().splits_received();
  }
  EXPECT_GT(splits[0], splits[1]);
  EXPECT_GT(splits[1], 0u);
}

TEST(ReceiverArea, OptionsItCannotHonourAreRefused) {
  const Fixture& f = test::terrain_fixture(30000, 5);
  Server server(f.catalogue);
  client::ReceiverOptions prefetch = area_options(16);
  prefetch.prefetch = true;
  EXPECT_THROW(client::ReceiverClient(server.url(), prefetch), Error);
  EXPECT_THROW(client::ReceiverClient(server.url(), area_options(0)), Error);
}

// The measured PSNR (docs/results and the CHANGELOG say it) with a margin: the bound catches a client that
// stops early or draws a broken mesh, not a change of a fraction of a dB.
constexpr double kBunnyPsnrBound = 30;

TEST(ReceiverArea, ItsBunnyIsCloseToLocalRefinementsByPsnr) {
  PMS_REQUIRE_SHARED_MODEL(model, "bunny.ply.xz");
  const Fixture& f = test::file_fixture(model.string(), "bunny");
  Server server(f.catalogue);
  client::ReceiverClient area(server.url(), area_options(client::ReceiverOptions{}.stop_area));
  client::ReceiverClient error(server.url());
  area.open("bunny");
  error.open("bunny");
  for (Camera camera : test::orbit_path(f.hierarchy, 4, 0.7f)) {
    camera.width = 640;
    camera.height = 480;
    area.settle(camera);
    error.settle(camera);
    const Image local = test::local_picture(f.snapped, camera, 1.0f);
    const double psnr = compare_images(test::picture(area.session().mesh(), camera, f.snapped), local).psnr;
    std::printf("area client: %llu splits, %llu B down; error ranking: %llu splits, %llu B down; PSNR %.2f dB\n",
                static_cast<unsigned long long>(area.session().splits_received()),
                static_cast<unsigned long long>(area.counters().payload_down),
                static_cast<unsigned long long>(error.session().splits_received()),
                static_cast<unsigned long long>(error.counters().payload_down), psnr);
    EXPECT_GT(psnr, kBunnyPsnrBound);
    EXPECT_EQ(compare_images(test::picture(error.session().mesh(), camera, f.snapped), local).psnr,
              std::numeric_limits<double>::infinity())
        << "the error ranking's mesh is local refinement's";
  }
}

}  // namespace
}  // namespace pms
