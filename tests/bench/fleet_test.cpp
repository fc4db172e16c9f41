// The fleet group end to end, short: 200 sessions on bunny from two load processes, then 20 of them flying
// for two seconds. Every packet the load processes received was checked against the model (a wrong or
// repeated split fails its session), so no failure, every flown session satisfied at its last camera and the
// server's splits_sent equal to what the sessions hold together say the server and the load process agree.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>

#include "bench/child_process.h"
#include "test_support.h"

namespace pms::bench {
namespace {

using nlohmann::json;

TEST(FleetBench, TwoHundredSessionsTwentyFlyingOnBunny) {
  if (test::shared_models_dir().empty()) GTEST_SKIP() << "../shared/models not found: the fleet flies the shared bunny";
  const auto out = test::temp_dir();
  const ChildResult run = run_child({PMSTREAM_BENCH_BINARY, "--only", "fleet", "--models", "bunny", "--fleet-sessions",
                                     "200", "--fleet-flying", "0,20", "--fleet-step-seconds", "2", "--fleet-processes",
                                     "2", "--shared", test::shared_models_dir().parent_path().string(), "--out",
                                     out.string()});
  ASSERT_TRUE(run.ok()) << run.failure();
  std::ifstream in(out / "fleet.json");
  ASSERT_TRUE(in) << "no fleet.json";
  const json fleet = json::parse(in);
  ASSERT_FALSE(fleet.contains("error")) << fleet["error"];
  const json& r = fleet["run"];
  EXPECT_EQ(r["sessions"], 200);
  EXPECT_EQ(r["open_failed"], 0) << r["failures"].dump();
  EXPECT_EQ(r["failed"], 0) << r["failures"].dump();
  EXPECT_GT(r["first_view_p50_ms"].get<double>(), 0);
  EXPECT_EQ(r["splits_sent"], r["splits_received"]);
  EXPECT_GT(r["splits_received"].get<uint64_t>(), 0u);
  ASSERT_EQ(r["steps"].size(), 2u);
  const json &idle = r["steps"][0], &flying = r["steps"][1];
  EXPECT_EQ(idle["flying"], 0);
  EXPECT_EQ(idle["views"], 0);  // held sessions send nothing
  EXPECT_EQ(flying["flying"], 20);
  EXPECT_EQ(flying["unsatisfied"], 0);
  EXPECT_EQ(flying["failed"], 0);
  // Moving cameras want new splits: VIEWs went out, each answered, and none without a frame flown.
  EXPECT_GT(flying["views"].get<uint64_t>(), 0u);
  EXPECT_EQ(flying["views"], flying["views_sent"]);
  EXPECT_LE(flying["views_sent"].get<uint64_t>(), flying["frames"].get<uint64_t>() + 4 * 20);
  EXPECT_GE(flying["p99_ms"].get<double>(), flying["p50_ms"].get<double>());
  EXPECT_GT(r["server_rss_held_bytes"].get<uint64_t>(), 0u);
  EXPECT_GT(r["peak_session_state_bytes"].get<uint64_t>(), 0u);
}

}  // namespace
}  // namespace pms::bench
