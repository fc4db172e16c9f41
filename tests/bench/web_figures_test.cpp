// The web group's figures out of a browser driver's JSON (bench/web/web_bench.mjs's shape), made up here:
// the fastest refinement runs, the frame rate leaving the first frame out, growth from the second lap, the median load,
// and the report marking each target met or not. The browser itself is never run here.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "bench/web_figures.h"

namespace pms::bench {
namespace {

using nlohmann::json;

// A drawn-frame log: frames at `period_ms`, the first one `first_ms` before the second.
json frame_log(size_t frames, double period_ms, double first_ms, double step_ms) {
  json log = json::array();
  double t = 0;
  for (size_t i = 0; i < frames; ++i) {
    log.push_back({{"t", t}, {"stepMs", step_ms + (i == frames - 1 ? 10 : 0)}, {"faces", 1000 + i}});
    t += i == 0 ? first_ms : period_ms;
  }
  return log;
}

// Animation-frame callbacks' thread CPU times: `ms` each, the last one 10 ms more.
json frame_cpu(size_t frames, double ms) {
  json out = json::array();
  for (size_t i = 0; i < frames; ++i) out.push_back(ms + (i == frames - 1 ? 10 : 0));
  return out;
}

json browser_json() {
  json flights = json::object();
  for (const char* mode : {"sender", "receiver"})
    flights[mode] = {{"log", frame_log(101, 50, 500, 1.5)},
                     {"frameCpuMs", frame_cpu(101, 2.5)},
                     {"downBytes", 12345},
                     {"faces", 2000},
                     {"settledBeforeFlight", true},
                     {"errors", json::array()}};
  json laps = json::array();
  for (uint64_t heap : {100, 200, 204, 206, 208})
    laps.push_back({{"frames", 10}, {"heapUsedBytes", heap}, {"wasmBytes", 1000}});
  return {{"browser", "test"},
          {"firstPicture",
           {{{"ms", 900}, {"downBytes", 10}, {"upBytes", 1}, {"siteBytes", 500}, {"errors", json::array()}},
            {{"ms", 300}, {"downBytes", 20}, {"upBytes", 2}, {"siteBytes", 600}, {"errors", json::array()}},
            {{"ms", 700}, {"downBytes", 30}, {"upBytes", 3}, {"siteBytes", 700}, {"errors", {"console: boom"}}}}},
          {"refine",
           {{{"ops", 700}, {"seconds", 1.0}}, {{"ops", 600}, {"seconds", 1.0}}, {{"ops", 650}, {"seconds", 1.0}}}},
          {"flights", flights},
          {"replay",
           {{"frames", 101},
            {"streamed", frame_log(101, 50, 500, 1)},
            {"replayed", frame_log(101, 40, 500, 1)},
            {"errors", json::array()}}},
          {"memory", {{"laps", laps}, {"errors", json::array()}}}};
}

const json kNative = {
    {{"ops", 1000}, {"seconds", 1.0}}, {{"ops", 900}, {"seconds", 1.0}}, {{"ops", 1100}, {"seconds", 1.0}}};

TEST(WebFigures, RatiosMediansAndGrowth) {
  const WebFigures f = web_figures(browser_json(), kNative);
  // The fastest run of each side.
  EXPECT_DOUBLE_EQ(f.native_ops_per_s, 1100);
  EXPECT_DOUBLE_EQ(f.wasm_ops_per_s, 700);
  EXPECT_DOUBLE_EQ(f.refine_ratio(), 700.0 / 1100);
  // The median load is the 700 ms one: its bytes are the ones reported.
  EXPECT_DOUBLE_EQ(f.first_picture_median_ms, 700);
  EXPECT_EQ(f.model_bytes, 33u);
  EXPECT_EQ(f.site_bytes, 700u);
  // The first frame's long interval is left out: 20 fps against 25.
  EXPECT_DOUBLE_EQ(f.streamed_fps, 20);
  EXPECT_DOUBLE_EQ(f.replayed_fps, 25);
  EXPECT_DOUBLE_EQ(f.fps_ratio(), 0.8);
  // From the second lap (200) to the fifth (208), not from the first.
  EXPECT_NEAR(f.heap_growth(), 0.04, 1e-12);
  EXPECT_DOUBLE_EQ(f.wasm_growth(), 0);
  ASSERT_EQ(f.modes.size(), 2u);
  EXPECT_EQ(f.modes[0].frames, 101u);
  // CPU from the traced callbacks, step from the page's clock; one slow frame in 101 is past the 99th
  // percentile's rank.
  EXPECT_EQ(f.modes[0].cpu_frames, 101u);
  EXPECT_DOUBLE_EQ(f.modes[0].cpu_p50_ms, 2.5);
  EXPECT_DOUBLE_EQ(f.modes[0].cpu_p99_ms, 2.5);
  EXPECT_DOUBLE_EQ(f.modes[0].step_p50_ms, 1.5);
  EXPECT_DOUBLE_EQ(f.modes[0].step_p99_ms, 1.5);
  ASSERT_EQ(f.page_errors.size(), 1u);
  EXPECT_EQ(f.page_errors[0], "first picture: console: boom");
}

TEST(WebFigures, ReportMarksEachTarget) {
  const std::string report = web_report(web_figures(browser_json(), kNative), 60);
  EXPECT_NE(report.find("| WASM refinement / native"), std::string::npos);
  // Met: refinement 0.64 ≥ 0.6, first picture 700 ≤ 1000, sender p99 ≤ 4, both growths ≤ 5 %; missed: fps 0.8.
  size_t not_met = 0, met = 0;
  for (size_t at = report.find("| met"); at != std::string::npos; at = report.find("| met", at + 1)) ++met;
  for (size_t at = report.find("not met"); at != std::string::npos; at = report.find("not met", at + 1)) ++not_met;
  EXPECT_EQ(met, 5u);
  EXPECT_EQ(not_met, 1u);
  EXPECT_NE(report.find("console: boom"), std::string::npos);
}

TEST(WebFigures, AnUntracedFlightDoesNotMeetTheCpuTarget) {
  json browser = browser_json();
  browser["flights"]["sender"].erase("frameCpuMs");
  const WebFigures f = web_figures(browser, kNative);
  for (const ModeFlight& m : f.modes) EXPECT_EQ(m.cpu_frames, m.mode == "sender" ? 0u : 101u) << m.mode;
  const std::string report = web_report(f, 60);
  const size_t row = report.find("| page CPU per frame, sender p99");
  ASSERT_NE(row, std::string::npos);
  const std::string line = report.substr(row, report.find('\n', row) - row);
  EXPECT_NE(line.find("not measured"), std::string::npos);
  EXPECT_NE(line.find("not met"), std::string::npos);
}

TEST(WebFigures, EmptyRunsGiveZerosNotNaN) {
  const WebFigures f = web_figures(json{{"firstPicture", json::array()},
                                        {"refine", json::array()},
                                        {"flights", json::object()},
                                        {"replay", {{"streamed", json::array()}, {"replayed", json::array()}}},
                                        {"memory", {{"laps", json::array()}}}},
                                   json::array());
  EXPECT_EQ(f.refine_ratio(), 0);
  EXPECT_EQ(f.fps_ratio(), 0);
  EXPECT_EQ(f.heap_growth(), 0);
  EXPECT_FALSE(figures_json(f).dump().empty());
}

}  // namespace
}  // namespace pms::bench
