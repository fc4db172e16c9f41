// The `pmstream` binary end to end (docs/cli.md contracts): build/info/refine on a generated mesh,
// JSON fields, exact reconstruction through files, and one-line errors with a non-zero exit code.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <nlohmann/json.hpp>

#include <array>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "child_process.h"
#include "client/http_connection.h"
#include "io/mesh.h"
#include "io/shapes.h"
#include "test_support.h"

namespace pms {
namespace {

using RunResult = test::CliRun;
RunResult run(const std::string& args) { return test::run_pmstream(args); }

TEST(Cli, BuildInfoRefineRoundTrip) {
  const auto dir = test::temp_dir();
  Mesh input = make_torus(40, 16, 2.0f, 0.5f);
  const std::string ply = (dir / "torus.ply").string(), pms_path = (dir / "torus.pms").string();
  save_ply(input, ply);

  const RunResult build = run("build " + ply + " -o " + pms_path + " --json");
  ASSERT_EQ(build.exit_code, 0) << build.err;
  const auto stats = nlohmann::json::parse(build.out);
  for (const char* field : {"input_vertices", "input_faces", "base_vertices", "base_faces", "vsplits", "tree_id_bits",
                            "node_id_bits", "max_depth", "seconds", "peak_rss_mb", "output_bytes"})
    EXPECT_TRUE(stats.contains(field)) << field;
  EXPECT_EQ(stats["input_faces"], input.face_count());
  EXPECT_EQ(stats["vsplits"].get<uint64_t>() + stats["base_vertices"].get<uint64_t>(), input.vertex_count());

  const RunResult info = run("info " + pms_path + " --json");
  ASSERT_EQ(info.exit_code, 0) << info.err;
  const auto info_stats = nlohmann::json::parse(info.out);
  for (const char* field : {"input_vertices", "input_faces", "base_vertices", "base_faces", "vsplits", "tree_id_bits",
                            "node_id_bits", "max_depth"})
    EXPECT_EQ(info_stats[field], stats[field]) << field;
  // The records: every split has one, a whole number of bytes holds them all, tables come with them.
  const double record_bits = info_stats["record_bits_per_split"].get<double>() * stats["vsplits"].get<double>();
  EXPECT_GT(record_bits, 0);
  EXPECT_EQ(info_stats["record_bytes"].get<uint64_t>(), uint64_t(std::ceil(record_bits / 8 - 1e-6)));
  EXPECT_GT(info_stats["record_table_bytes"].get<uint64_t>(), 0u);
  EXPECT_EQ(info_stats["record_position_bits"], 16);

  const std::string full = (dir / "full.ply").string(), coarse = (dir / "coarse.ply").string();
  const RunResult refine = run("refine " + pms_path + " --full -o " + full + " --json");
  ASSERT_EQ(refine.exit_code, 0) << refine.err;
  const Mesh finest = load_mesh(full);
  EXPECT_EQ(finest.face_count(), input.face_count());
  EXPECT_EQ(finest.vertex_count(), input.vertex_count());
  EXPECT_EQ(nlohmann::json::parse(refine.out)["vsplits_applied"], stats["vsplits"]);

  const RunResult base = run("refine " + pms_path + " --splits 0 -o " + coarse);
  ASSERT_EQ(base.exit_code, 0) << base.err;
  EXPECT_EQ(load_mesh(coarse).face_count(), stats["base_faces"].get<size_t>());
}

// `demo --model`: the user's own mesh is built (then reused), streamed over loopback, and compared with
// the view-independent flight; the report carries the table.
TEST(Cli, DemoStreamsTheUsersOwnModel) {
  const auto dir = test::temp_dir();
  const std::string ply = (dir / "torus.ply").string(), out = (dir / "demo").string();
  save_ply(make_torus(60, 24, 2.0f, 0.5f), ply);
  const RunResult first = run("demo --model " + ply + " --out " + out + " --frames 12");
  ASSERT_EQ(first.exit_code, 0) << first.err;
  EXPECT_NE(first.out.find("building " + ply), std::string::npos) << first.out;
  EXPECT_NE(first.out.find("server:    torus on 127.0.0.1:"), std::string::npos) << first.out;
  EXPECT_NE(first.out.find("view-independent bytes down"), std::string::npos) << first.out;
  std::ifstream report(dir / "demo" / "report.md");
  const std::string text((std::istreambuf_iterator<char>(report)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("| 12 |"), std::string::npos) << text;
  EXPECT_TRUE(std::filesystem::exists(dir / "demo" / "snapshots" / "frame_0000.png"));

  const RunResult again = run("demo --headless --model " + ply + " --out " + out + " --frames 2");
  ASSERT_EQ(again.exit_code, 0) << again.err;
  EXPECT_NE(again.out.find("using the cached build"), std::string::npos) << again.out;

  const RunResult served =
      run("demo --model " + (dir / "demo" / "torus.pms").string() + " --out " + out + " --frames 2");
  ASSERT_EQ(served.exit_code, 0) << served.err;
  EXPECT_EQ(served.out.find("building"), std::string::npos) << "a .pms is streamed as it is";

  const RunResult missing = run("demo --model " + (dir / "nope.ply").string() + " --out " + out);
  EXPECT_NE(missing.exit_code, 0);
  EXPECT_NE(missing.err.find("nope.ply: no such file"), std::string::npos) << missing.err;
}

// `demo --serve` (what a terminal gets): the model served on loopback, the page's link printed, the page and
// the catalogue answered over HTTP, a clean stop on SIGINT (Ctrl-C). Every line is waited for under a deadline.
TEST(Cli, DemoServesThePageUntilCtrlC) {
  using std::chrono::seconds;
  const auto dir = test::temp_dir();
  const std::string ply = (dir / "torus.ply").string(), root = (dir / "site").string();
  save_ply(make_torus(40, 16, 2.0f, 0.5f), ply);
  std::filesystem::create_directories(root);
  const std::string page = "<!doctype html><title>pmstream</title>\n";
  std::ofstream(root + "/index.html") << page;
  test::ChildProcess demo(PMSTREAM_BINARY, {"demo", "--serve", "--model", ply, "--out", (dir / "demo").string(),
                                            "--port", "0", "--http-port", "0", "--web-root", root});
  std::string link;
  for (std::string line; link.empty() && !(line = demo.next_line(seconds(60))).empty();)
    if (line.rfind("page:", 0) == 0) link = line.substr(line.find("http://"));
  ASSERT_FALSE(link.empty()) << "no page: line";
  EXPECT_NE(link.find("/#model=torus&mode=sender&tau=1&eye="), std::string::npos) << link;
  const size_t port_at = link.find(':', 5) + 1;
  client::HttpConnection http(client::parse_http_url(link.substr(0, link.find('/', port_at))));
  const client::HttpAnswer models = http.get("/models");
  EXPECT_EQ(models.status, 200);
  EXPECT_NE(std::string(models.body.begin(), models.body.end()).find("\"torus\""), std::string::npos);
  const client::HttpAnswer index = http.get("/");
  EXPECT_EQ(index.status, 200);
  EXPECT_EQ(std::string(index.body.begin(), index.body.end()), page);
  demo.signal(SIGINT);
  std::string last;
  for (std::string line; !(line = demo.next_line(seconds(30))).empty();) last = line;
  EXPECT_EQ(last.rfind("stopped:", 0), 0u) << last;
  EXPECT_EQ(demo.wait(seconds(30)), 0);
}

TEST(Cli, ErrorsAreOneLineNamingTheFile) {
  const auto dir = test::temp_dir();
  const std::string missing = (dir / "nope.ply").string();
  const RunResult r = run("build " + missing + " -o " + (dir / "x.pms").string());
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find(missing), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;

  const std::string garbage = (dir / "garbage.pms").string();
  std::ofstream(garbage) << "this is not a pms file at all, just text that is long enough to look at";
  const RunResult info = run("info " + garbage);
  EXPECT_NE(info.exit_code, 0);
  EXPECT_NE(info.err.find(garbage), std::string::npos) << info.err;
  EXPECT_EQ(std::count(info.err.begin(), info.err.end(), '\n'), 1) << info.err;

  const RunResult both = run("refine " + garbage + " -o " + (dir / "o.ply").string());
  EXPECT_NE(both.exit_code, 0);
}

// Text mode: SIGUSR1 prints the totals so far under "stats:" and the server runs on; only the stop prints
// "stopped:". Every line is waited for under a deadline.
TEST(Cli, ServeSigusr1PrintsStatsAndOnlyTheStopPrintsStopped) {
  using std::chrono::seconds;
  const std::string pms_path = (test::temp_dir() / "terrain.pms").string();
  ASSERT_EQ(run("build terrain:2000 -o " + pms_path).exit_code, 0);
  test::ChildProcess serve(PMSTREAM_BINARY,
                           {"serve", pms_path, "--host", "127.0.0.1", "--port", "0", "--http-port", "0"});
  // "serving terrain: ...", then a listening line per port: the signals are blocked by then.
  for (const char* start : {"serving ", "listening on ", "listening on "})
    ASSERT_EQ(serve.next_line(seconds(30)).rfind(start, 0), 0u) << start;
  const auto lines_after = [&serve](int signal) {
    serve.signal(signal);
    std::vector<std::string> lines;
    for (int i = 0; i < 4; ++i) lines.push_back(serve.next_line(seconds(30)));
    return lines;
  };
  for (int round = 0; round < 2; ++round) {
    const std::vector<std::string> stats = lines_after(SIGUSR1);
    EXPECT_EQ(stats[0].rfind("stats: ", 0), 0u) << stats[0];
    EXPECT_EQ(stats[1].rfind("tables: ", 0), 0u) << stats[1];
    EXPECT_EQ(stats[2].rfind("http: ", 0), 0u) << stats[2];
    EXPECT_EQ(stats[3].rfind("ws: ", 0), 0u) << stats[3];
  }
  const std::vector<std::string> stopped = lines_after(SIGTERM);
  EXPECT_EQ(stopped[0].rfind("stopped: ", 0), 0u) << stopped[0];
  EXPECT_EQ(stopped[2].rfind("http: ", 0), 0u) << stopped[2];
  EXPECT_EQ(stopped[3].rfind("ws: ", 0), 0u) << stopped[3];
  EXPECT_EQ(serve.wait(seconds(30)), 0);
}

}  // namespace
}  // namespace pms
