// The server benches' plumbing against a real `pmstream serve --json`: its counters agree with what a
// LoadClient received, a resume re-sends nothing, and a server that does not report is an error that
// says why (E11 and the soak read the server only through ServeChild).
#include <utility>  // before asio with C++20

#include <gtest/gtest.h>
#include <boost/asio.hpp>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>

#include "apps/camera_path.h"
#include "bench/serve_child.h"
#include "client/load_client.h"
#include "common/error.h"
#include "spm/pms_file.h"
#include "test_support.h"

namespace pms::bench {
using app::make_camera_path;
using app::PathKind;
using app::PathOptions;
namespace {

using nlohmann::json;

json full_stats_line() {
  json line = {{"event", "stats"}, {"uptime_s", 1.5}, {"cpu_s", 0.25}};
  for (const char* name :
       {"sessions_opened", "sessions_active", "sessions_refused", "sessions_timed_out", "sessions_failed",
        "protocol_errors", "accept_failures", "longest_turn_us", "bytes_in", "bytes_out", "splits_sent", "errors_sent",
        "peak_state_bytes", "peak_buffer_bytes", "rss_bytes", "peak_rss_bytes"})
    line[name] = 7;
  return line;
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(ServeStats, EveryCounterIsRequired) {
  json line = full_stats_line();
  const ServeStats s = parse_serve_stats(line);
  EXPECT_EQ(s.bytes_out, 7u);
  EXPECT_EQ(s.peak_rss_bytes, 7u);
  EXPECT_DOUBLE_EQ(s.cpu_s, 0.25);
  line.erase("peak_state_bytes");
  EXPECT_NE(error_of([&] { parse_serve_stats(line); }).find("no counter peak_state_bytes"), std::string::npos);
  line = full_stats_line();
  line["bytes_out"] = "12";  // a string is not a count
  EXPECT_NE(error_of([&] { parse_serve_stats(line); }).find("bytes_out"), std::string::npos);
  line = full_stats_line();
  line["splits_sent"] = -1;
  EXPECT_NE(error_of([&] { parse_serve_stats(line); }).find("splits_sent"), std::string::npos);
}

// A small model built by the binary, as the benches build theirs.
std::filesystem::path small_model(const std::filesystem::path& dir) {
  const std::string pms = (dir / "terrain.pms").string();
  const test::CliRun build = test::run_pmstream("build terrain:20000 -o " + pms);
  EXPECT_EQ(build.exit_code, 0) << build.err;
  return pms;
}

TEST(ServeChild, CountersAgreeWithWhatTheClientReceived) {
  const auto pms = small_model(test::temp_dir());
  const auto file = PmsFile::open(pms.string());
  ServeChild server(PMSTREAM_BINARY, {pms.string()});
  EXPECT_GT(server.port(), 0);
  ASSERT_EQ(server.listening()["models"].size(), 1u);
  EXPECT_EQ(server.listening()["models"][0]["name"], "terrain");
  EXPECT_EQ(server.stats().sessions_opened, 0u);

  client::LoadClientOptions options;
  options.model = &file->model();
  client::LoadClient client("127.0.0.1", server.port(), "terrain", options);
  PathOptions path_options;
  path_options.frames = 8;
  const std::vector<Camera> path = make_camera_path(PathKind::zoom, file->model(), path_options);
  client.open(false);
  client.view(path[4], 1);
  const uint64_t first = client.splits_received();
  EXPECT_GT(first, 0u);
  // Resumed on the leaves it holds, the same view needs nothing; a closer one only what it adds. A split
  // sent twice would have thrown (it would no longer be of a held leaf).
  client.drop();
  client.open(true);
  client.view(path[4], 1);
  EXPECT_EQ(client.splits_received(), first);
  client.view(path[7], 1);
  EXPECT_GT(client.splits_received(), first);
  const ServeStats during = server.stats();
  EXPECT_EQ(during.sessions_opened, 2u);
  EXPECT_GT(during.rss_bytes, 0u);
  client.drop();

  const ServeStats stopped = server.stop();
  EXPECT_EQ(stopped.line["event"], "stopped");
  EXPECT_EQ(stopped.splits_sent, client.splits_received());
  EXPECT_GE(stopped.peak_rss_bytes, during.rss_bytes);
  EXPECT_GT(stopped.bytes_out, stopped.bytes_in);
  EXPECT_EQ(stopped.sessions_failed + stopped.protocol_errors, 0u);
}

// One HTTP/1.1 request that asks the server to close after it; the whole answer as text.
std::string http_exchange(uint16_t port, const std::string& target, const std::string& fields = "") {
  namespace asio = boost::asio;
  asio::io_context io;
  asio::ip::tcp::socket socket(io);
  socket.connect({asio::ip::make_address("127.0.0.1"), port});
  asio::write(socket,
              asio::buffer("GET " + target + " HTTP/1.1\r\nHost: t\r\nConnection: close\r\n" + fields + "\r\n"));
  std::string answer;
  boost::system::error_code ec;
  asio::read(socket, asio::dynamic_buffer(answer), ec);  // to the end of the stream
  return answer;
}

TEST(ServeChild, ServesHttpBesideTcpAndCountsIt) {
  const auto pms = small_model(test::temp_dir());
  ServeChild server(PMSTREAM_BINARY, {pms.string(), "--http-port", "0"});
  const uint16_t http_port = server.listening()["http_port"];
  EXPECT_GT(http_port, 0);
  EXPECT_NE(http_port, server.port());
  const std::string models = http_exchange(http_port, "/models");
  EXPECT_EQ(models.rfind("HTTP/1.1 200 OK\r\n", 0), 0u) << models;
  EXPECT_NE(models.find("\"name\":\"terrain\""), std::string::npos) << models;
  const std::string version = server.listening()["models"][0]["version"];
  const std::string base = http_exchange(http_port, "/models/terrain/" + version + "/base");
  EXPECT_NE(base.find("Cache-Control: max-age=31536000, immutable"), std::string::npos) << base;
  EXPECT_EQ(http_exchange(http_port, "/models/other/base").rfind("HTTP/1.1 404", 0), 0u);
  const ServeStats stopped = server.stop();
  EXPECT_EQ(stopped.line["http"]["requests"], 3);
  EXPECT_EQ(stopped.line["http"]["client_errors"], 1);
  EXPECT_EQ(stopped.sessions_opened, 0u);  // HTTP has no sessions
}

// "element face N" of a PLY's header; 0 when there is none.
uint64_t ply_face_count(const std::filesystem::path& ply) {
  std::ifstream in(ply, std::ios::binary);
  for (std::string line; std::getline(in, line) && line != "end_header";)
    if (line.rfind("element face ", 0) == 0) return std::stoull(line.substr(13));
  return 0;
}

// `stream --mode receiver` with a frame budget and prefetch: the JSON reports the work carried between
// frames, and the flight ends on the faces of the unbudgeted one (the budget changes when, not what).
TEST(ServeChild, StreamReceiverWithAFrameBudgetReportsWhatItCarried) {
  const auto dir = test::temp_dir();
  const auto pms = small_model(dir);
  ServeChild server(PMSTREAM_BINARY, {pms.string(), "--http-port", "0"});
  const uint16_t http_port = server.listening()["http_port"];
  const std::string path = (dir / "zoom.json").string();
  ASSERT_EQ(test::run_pmstream("path zoom --model " + pms.string() + " --frames 12 -o " + path).exit_code, 0);
  const std::string stream = "stream --mode receiver --server http://127.0.0.1:" + std::to_string(http_port) +
                             " --model terrain --path " + path + " --ids-per-request 16 --json";
  const test::CliRun plain = test::run_pmstream(stream + " --save-mesh " + (dir / "plain.ply").string());
  const test::CliRun budgeted =
      test::run_pmstream(stream + " --frame-answers 2 --prefetch --save-mesh " + (dir / "budgeted.ply").string());
  ASSERT_EQ(plain.exit_code, 0) << plain.err;
  ASSERT_EQ(budgeted.exit_code, 0) << budgeted.err;
  const json a = json::parse(plain.out), b = json::parse(budgeted.out);
  EXPECT_EQ(a["frame_answers"], 0);
  EXPECT_EQ(a["frames_unsatisfied"], 0);
  EXPECT_EQ(a["settle_frames"], 1);
  EXPECT_EQ(b["frame_answers"], 2);
  EXPECT_EQ(b["prefetch"], true);
  EXPECT_GT(b["frames_unsatisfied"].get<uint64_t>(), 0u);
  uint64_t carried = 0;
  for (const json& frame : b["frames"]) {
    for (const char* field :
         {"satisfied", "queued", "in_flight", "cancelled", "stale_arrivals", "prefetched", "prefetch_used"})
      EXPECT_TRUE(frame.contains(field)) << field;
    carried += frame["in_flight"].get<uint64_t>();
  }
  EXPECT_GT(carried, 0u) << "GETs left in flight at a frame's end";
  for (const char* total : {"cancelled", "stale_arrivals", "prefetched", "prefetch_used"})
    EXPECT_TRUE(b.contains(total)) << total;
  // Settled on the last camera, both meshes are its local refinement (Receiver.* checks face by face).
  EXPECT_EQ(ply_face_count(dir / "plain.ply"), ply_face_count(dir / "budgeted.ply"));
  EXPECT_GT(ply_face_count(dir / "plain.ply"), 0u);
}

// The HTTP size limits are the command line's: a URL one byte over --http-max-url-bytes gets 414, one at
// the limit is served; header fields over --http-max-header-bytes get 431, a request line over it 414.
TEST(ServeChild, HttpSizeLimitsComeFromTheCommandLine) {
  const auto pms = small_model(test::temp_dir());
  ServeChild server(PMSTREAM_BINARY,
                    {pms.string(), "--http-port", "0", "--http-max-url-bytes", "48", "--http-max-header-bytes", "200"});
  const uint16_t http_port = server.listening()["http_port"];
  const std::string base = "/models/terrain/" + server.listening()["models"][0]["version"].get<std::string>() + "/base";
  const std::string at_limit = base + std::string(48 - base.size(), '/');  // a route, not found
  ASSERT_EQ(at_limit.size(), 48u);
  EXPECT_EQ(http_exchange(http_port, at_limit).rfind("HTTP/1.1 404", 0), 0u);
  EXPECT_EQ(http_exchange(http_port, at_limit + "/").rfind("HTTP/1.1 414", 0), 0u);
  EXPECT_EQ(http_exchange(http_port, base).rfind("HTTP/1.1 200", 0), 0u);
  EXPECT_EQ(http_exchange(http_port, "/models", "X: " + std::string(200, 'x') + "\r\n").rfind("HTTP/1.1 431", 0), 0u);
  EXPECT_EQ(http_exchange(http_port, "/models?" + std::string(200, 'x')).rfind("HTTP/1.1 414", 0), 0u);
}

TEST(ServeChild, AServerThatDoesNotStartSaysWhy) {
  const std::string error =
      error_of([] { ServeChild server(PMSTREAM_BINARY, {(test::temp_dir() / "missing.pms").string()}); });
  EXPECT_NE(error.find("without its \"listening\" line"), std::string::npos) << error;
  EXPECT_NE(error.find("missing.pms"), std::string::npos) << error;  // serve's own one-line error
}

TEST(ServeChild, ALineThatIsNotJsonIsAnError) {
  // echo prints its arguments ("serve x --json ...") as a plain text line, as a serve without --json would.
  const std::string error = error_of([] { ServeChild server("/bin/echo", {"x"}); });
  EXPECT_NE(error.find("not a JSON object: serve x --json"), std::string::npos) << error;
}

}  // namespace
}  // namespace pms::bench
