// The receiver-driven client against the HTTP server over real loopback: its mesh is local refinement's
// for the same view and τ, a second lap asks for nothing, the ids asked for match the splits received, a
// frame budget carries work between frames (cancelling what a new view no longer wants, prefetching along
// the path) and still ends on local refinement's mesh, and a server that stalls or closes mid-answer is a
// clear error within the deadline.
#include <utility>  // before asio with C++20 (docs/architecture.md, "Stack")

#include <gtest/gtest.h>
#include <algorithm>
#include <atomic>
#include <boost/asio.hpp>
#include <chrono>
#include <string>
#include <thread>

#include "client/http_connection.h"
#include "client/receiver_client.h"
#include "client/streaming_client.h"
#include "client/transport.h"
#include "common/error.h"
#include "io/shapes.h"
#include "protocol/split_request.h"
#include "server/http_server.h"
#include "server/limits.h"
#include "server/tcp_server.h"
#include "streaming_fixture.h"

namespace pms {
namespace {

using test::faces_by_id;
using test::Fixture;
using test::local_faces;
using test::make_fixture;
using test::orbit_path;

const Fixture& terrain() {
  return test::terrain_fixture(30000, 5);
}

using Server = test::LoopbackHttpServer;

TEST(Receiver, MeshEqualsLocalRefinementAndASecondLapAsksForNothing) {
  const Fixture& f = terrain();
  Server server(f.catalogue);
  client::ReceiverOptions options;
  options.ids_per_request = 16;  // several requests per round, so pipelining is exercised
  client::ReceiverClient client(server.url(), options);
  ASSERT_EQ(client.list(), std::vector<std::string>{"terrain"});
  client.open("terrain");
  const std::vector<Camera> path = orbit_path(f.hierarchy, 10, 0.3f);
  uint64_t lap1_requests = 0;
  for (const Camera& camera : path) {
    const client::ReceiverFrame r = client.frame(camera);
    lap1_requests += r.split_requests;
    EXPECT_EQ(r.report.up_bytes > 0, r.split_requests > 0);
    EXPECT_GE(r.report.down_bytes, r.payload_down);
    EXPECT_TRUE(r.satisfied);  // no budget: nothing carried to the next frame, nothing cancelled
    EXPECT_EQ(r.queued + r.in_flight + r.cancelled + r.stale_arrivals + r.prefetched, 0u);
    EXPECT_EQ(faces_by_id(client.session().mesh()), local_faces(f.snapped, camera, 1.0f))
        << "frame " << r.report.frame << " differs from local refinement";
  }
  EXPECT_GT(lap1_requests, 1u);
  EXPECT_GT(client.session().splits_received(), 0u);
  EXPECT_EQ(server.http.stats().splits_served.load(), client.session().splits_received())
      << "every split asked for once, and only what was attached";
  const uint64_t requests_after_lap1 = server.http.stats().requests.load();
  for (const Camera& camera : path) {
    const client::ReceiverFrame r = client.frame(camera);
    EXPECT_EQ(r.split_requests, 0u);
    EXPECT_EQ(r.report.up_bytes, 0u);
    EXPECT_EQ(r.report.down_bytes, 0u);
  }
  EXPECT_EQ(server.http.stats().requests.load(), requests_after_lap1) << "a second lap sends no request";
}

// Frames until the view is satisfied (a budgeted client finishes a view over several), at most `most`.
uint32_t frames_to_satisfy(client::ReceiverClient& client, const Camera& camera, uint32_t most = 500) {
  for (uint32_t n = 1; n <= most; ++n)
    if (client.frame(camera).satisfied) return n;
  return most + 1;
}

// With a budget of a few answers a frame, a frame ends with its view unfinished, GETs in flight and ids
// queued; they carry over, and holding the last camera the client ends on local refinement's mesh.
// (A time budget is the same loop with a clock; the next test checks only where it ends.)
TEST(Receiver, AFrameBudgetCarriesTheRestAndConvergesToLocalRefinement) {
  const Fixture& f = terrain();
  for (const client::FetchPolicy fetch : {client::FetchPolicy::lists, client::FetchPolicy::blocks}) {
    Server server(f.catalogue);
    client::ReceiverOptions options;
    options.fetch = fetch;
    options.ids_per_request = 16;
    options.frame_answers = 2;
    client::ReceiverClient client(server.url(), options);
    client.open("terrain");
    const std::vector<Camera> path = orbit_path(f.hierarchy, 10, 0.3f);
    uint32_t unfinished = 0, carried = 0;
    for (const Camera& camera : path) {
      const client::ReceiverFrame r = client.frame(camera);
      unfinished += !r.satisfied;
      carried += r.in_flight > 0 && r.queued > 0;
      EXPECT_LE(r.in_flight, options.http.in_flight);
    }
    EXPECT_GT(unfinished, 5u) << client::fetch_policy_name(fetch);
    EXPECT_GT(carried, 0u) << "frames ending with GETs in flight and ids queued";
    const uint32_t frames = frames_to_satisfy(client, path.back());
    EXPECT_GT(frames, 1u);
    EXPECT_LE(frames, 500u);
    EXPECT_EQ(faces_by_id(client.session().mesh()), local_faces(f.snapped, path.back(), 1.0f))
        << client::fetch_policy_name(fetch) << ": the budgeted flight ends on local refinement's mesh";
    EXPECT_GE(server.http.stats().splits_served.load(), client.session().splits_received());
  }
}

TEST(Receiver, ATimeBudgetEndsFramesEarlyAndStillConverges) {
  const Fixture& f = terrain();
  Server server(f.catalogue);
  client::ReceiverOptions options;
  options.ids_per_request = 16;
  options.frame_budget_ms = 1;  // about an answer a frame
  client::ReceiverClient client(server.url(), options);
  client.open("terrain");
  const Camera camera = orbit_path(f.hierarchy, 10, 0.3f).back();
  EXPECT_GT(frames_to_satisfy(client, camera), 1u);
  EXPECT_EQ(faces_by_id(client.session().mesh()), local_faces(f.snapped, camera, 1.0f));
}

// A view jump while ids are queued for the old view: the new ranking drops those it does not want before
// they are sent, answers already on their way arrive stale and are kept, and the mesh still converges.
TEST(Receiver, AViewJumpCancelsQueuedRequestsAndStillConverges) {
  const Fixture& f = terrain();
  Server server(f.catalogue);
  client::ReceiverOptions options;
  options.ids_per_request = 8;
  options.frame_answers = 1;
  client::ReceiverClient client(server.url(), options);
  client.open("terrain");
  const Camera near = orbit_path(f.hierarchy, 10, 0.3f).back();
  const Camera across = orbit_path(f.hierarchy, 10, 0.3f + 3.1f).back();
  client::ReceiverFrame first;
  for (int n = 0; n < 30; ++n) first = client.frame(near);  // deep into the near view's part of the front
  ASSERT_FALSE(first.satisfied);
  ASSERT_GT(first.queued, 0u);
  ASSERT_GT(first.in_flight, 0u);
  const client::ReceiverFrame jump = client.frame(across);
  EXPECT_GT(jump.cancelled, 0u) << "ids queued for the old view, dropped unsent";
  EXPECT_LE(jump.cancelled, first.queued);
  frames_to_satisfy(client, across);
  EXPECT_GT(client.totals().stale_arrivals, 0u) << "GETs in flight at the jump, answered and attached";
  EXPECT_EQ(faces_by_id(client.session().mesh()), local_faces(f.snapped, across, 1.0f));
  EXPECT_EQ(client.totals().cancelled, jump.cancelled);
}

// Prefetch along a smooth path asks for splits a later frame uses, and changes no mesh: prefetched splits
// are held data, made only when a view wants them. Unbudgeted, every frame is local refinement's. Blocks
// fill the pipe with small GETs, so their prefetch goes as answers make room. (A budget of a few answers a
// frame leaves blocks behind the view on this path: nothing is prefetched while the view wants more.)
TEST(Receiver, PrefetchAlongASmoothPathIsUsedAndLeavesTheMeshAsItWas) {
  const Fixture& f = terrain();
  for (const client::FetchPolicy fetch : {client::FetchPolicy::lists, client::FetchPolicy::blocks}) {
    for (const uint32_t budget : {0u, 32u}) {
      SCOPED_TRACE(std::string(client::fetch_policy_name(fetch)) + ", budget " + std::to_string(budget));
      Server server(f.catalogue);
      client::ReceiverOptions options;
      options.fetch = fetch;
      options.ids_per_request = 16;
      options.frame_answers = budget;
      options.prefetch = true;
      client::ReceiverClient client(server.url(), options);
      client.open("terrain");
      const std::vector<Camera> path = orbit_path(f.hierarchy, 40, 0.3f);
      for (const Camera& camera : path) {
        const client::ReceiverFrame r = client.frame(camera);
        if (budget == 0) {
          EXPECT_TRUE(r.satisfied);
          EXPECT_EQ(faces_by_id(client.session().mesh()), local_faces(f.snapped, camera, 1.0f))
              << "frame " << r.report.frame << " with prefetch differs from local refinement";
        }
      }
      frames_to_satisfy(client, path.back());
      EXPECT_EQ(faces_by_id(client.session().mesh()), local_faces(f.snapped, path.back(), 1.0f));
      EXPECT_GT(client.totals().prefetched, 0u);
      EXPECT_GT(client.totals().prefetch_used, 0u);
      EXPECT_LE(client.totals().prefetch_used, client.totals().prefetched);
    }
  }
}

// Fetching by blocks brings whole subtree bands, more than the view needs, yet the mesh is still local
// refinement's: what the client holds beyond the view's needs changes nothing adapt() decides.
TEST(Receiver, BlocksGiveTheMeshOfLocalRefinement) {
  const Fixture& f = terrain();
  for (const uint32_t block_depth : {0u, 2u, 3u}) {
    Server server(f.catalogue);
    client::ReceiverOptions options;
    options.fetch = client::FetchPolicy::blocks;
    options.block_depth = block_depth;
    client::ReceiverClient client(server.url(), options);
    client.open("terrain");
    for (const Camera& camera : orbit_path(f.hierarchy, 8, 0.3f)) {
      client.frame(camera);
      EXPECT_EQ(faces_by_id(client.session().mesh()), local_faces(f.snapped, camera, 1.0f))
          << "block depth " << block_depth << " differs from local refinement";
    }
    EXPECT_GT(client.split_requests(), 0u);
    EXPECT_EQ(server.http.stats().split_requests.load(), client.split_requests());
    EXPECT_EQ(server.http.stats().splits_served.load(), client.session().splits_received())
        << "no block asked for twice, every record attached";
  }
}

// The leaves held, in code order (the slots are in arrival order, which differs between modes).
std::vector<VertexId> sorted_leaves(const client::ClientSession& session) {
  std::vector<VertexId> leaves = session.known_leaves();
  std::sort(leaves.begin(), leaves.end(), protocol::code_order);
  return leaves;
}

// Without descendant depth the client chooses exactly what the sender-driven server would send it: the same
// splits on the same path. With it (the default), a GET for a leaf far above τ brings some levels below it
// too: a few more splits held, the same mesh.
TEST(Receiver, ReceivesTheSplitsTheSenderDrivenModeSendsOnTheSamePath) {
  const Fixture& f = terrain();
  Server http(f.catalogue);
  server::TcpServer tcp(f.catalogue, server::ServerLimits{}, "127.0.0.1", 0);
  tcp.start();
  client::ReceiverOptions exact;
  exact.descendant_depth = 0;
  client::ReceiverClient receiver(http.url(), exact);
  receiver.open("terrain");
  client::ReceiverClient deep(http.url());
  deep.open("terrain");
  client::StreamingClient sender("127.0.0.1", tcp.port(), client::ClientOptions{1.0f});
  sender.open("terrain");
  for (const Camera& camera : orbit_path(f.hierarchy, 8, 0.7f)) {
    receiver.frame(camera);
    deep.frame(camera);
    sender.frame(camera);
    EXPECT_EQ(receiver.session().splits_received(), sender.session().splits_received());
    EXPECT_EQ(sorted_leaves(receiver.session()), sorted_leaves(sender.session()));
    EXPECT_GE(deep.session().splits_received(), sender.session().splits_received());
    EXPECT_EQ(faces_by_id(deep.session().mesh()), faces_by_id(sender.session().mesh()));
  }
  EXPECT_GT(deep.session().splits_received(), sender.session().splits_received()) << "some depth was asked for";
  // Each id asked for once, each bringing its one split; the id sets' codes counted as sent.
  EXPECT_EQ(receiver.totals().requested_ids, receiver.session().splits_received());
  EXPECT_GT(receiver.totals().request_code_bytes, 0u);
  EXPECT_LE(8 * receiver.totals().request_code_bytes, 27 * receiver.totals().requested_ids)
      << "issue 19's bits per requested id (cheng-ooi: 27)";
}

// The compact records carry v_t's normal and color: the client ends on local refinement's mesh with the
// same positions, normals and colors.
TEST(Receiver, AModelWithNormalsAndColorsEndsOnLocalRefinementsValues) {
  const Fixture& f = test::attributed_terrain();
  ASSERT_FALSE(f.hierarchy.normals.empty());
  ASSERT_FALSE(f.hierarchy.colors.empty());
  ASSERT_TRUE(f.catalogue->find(f.name)->tables->records().codec->has_normals());
  Server server(f.catalogue);
  client::ReceiverClient client(server.url());
  client.open(f.name);
  for (const Camera& camera : orbit_path(f.hierarchy, 6, 0.2f)) {
    client.frame(camera);
    EXPECT_EQ(faces_by_id(client.session().mesh()), local_faces(f.snapped, camera, 1.0f));
    EXPECT_EQ(test::vertices_by_id(client.session().mesh()), test::local_vertices(f.snapped, camera, 1.0f));
  }
  EXPECT_GT(client.session().splits_received(), 0u);
}

// A model's name comes from its file's: spaces, '%' and UTF-8 travel escaped (RFC 3986), both ways.
TEST(Receiver, AModelWhoseNameNeedsEscapesIsStreamedByName) {
  const std::string name = "terrain 50% \xC3\xBC";  // "terrain 50% ü"
  const Fixture f = make_fixture(make_terrain(4000, 2), name);
  Server server(f.catalogue);
  client::ReceiverClient client(server.url());
  ASSERT_EQ(client.list(), std::vector<std::string>{name});
  client.open(name);
  for (const Camera& camera : orbit_path(f.hierarchy, 4, 0.1f)) {
    client.frame(camera);
    EXPECT_EQ(faces_by_id(client.session().mesh()), local_faces(f.snapped, camera, 1.0f));
  }
  EXPECT_GT(client.session().splits_received(), 0u);
}

TEST(Receiver, SurvivesTheServerClosingIdleKeptAliveConnections) {
  const Fixture& f = terrain();
  server::HttpLimits limits;
  limits.idle_timeout_ms = 100;
  Server server(f.catalogue, limits);
  client::ReceiverClient client(server.url());
  client.open("terrain");
  const std::vector<Camera> path = orbit_path(f.hierarchy, 4, 0.1f);
  for (const Camera& camera : path) {
    std::this_thread::sleep_for(std::chrono::milliseconds(250));  // the server has closed the connection
    client.frame(camera);
    EXPECT_EQ(faces_by_id(client.session().mesh()), local_faces(f.snapped, camera, 1.0f));
  }
  EXPECT_GT(client.counters().connections, 1u);
}

// The same with GETs left in flight across the pause: their answers came before the close and are read
// from the socket; what was not yet written goes on a new connection.
TEST(Receiver, GetsInFlightSurviveTheServerClosingBetweenFrames) {
  const Fixture& f = terrain();
  server::HttpLimits limits;
  limits.idle_timeout_ms = 100;
  Server server(f.catalogue, limits);
  client::ReceiverOptions options;
  options.ids_per_request = 16;
  options.frame_answers = 2;
  client::ReceiverClient client(server.url(), options);
  client.open("terrain");
  const std::vector<Camera> path = orbit_path(f.hierarchy, 6, 0.1f);
  uint32_t paused_in_flight = 0;
  for (const Camera& camera : path) {
    const client::ReceiverFrame r = client.frame(camera);
    paused_in_flight += r.in_flight > 0;
    std::this_thread::sleep_for(std::chrono::milliseconds(250));
  }
  EXPECT_GT(paused_in_flight, 0u);
  frames_to_satisfy(client, path.back());
  EXPECT_EQ(faces_by_id(client.session().mesh()), local_faces(f.snapped, path.back(), 1.0f));
  EXPECT_GT(client.counters().connections, 1u);
}

// A hostile origin on loopback: reads a request, sends the start of an answer, then stalls or closes.
struct BrokenServer {
  explicit BrokenServer(bool close_mid_answer) : acceptor(io, {boost::asio::ip::make_address("127.0.0.1"), 0}) {
    thread = std::thread([this, close_mid_answer] {
      boost::asio::ip::tcp::socket socket(io);
      acceptor.accept(socket);
      char request[4096];
      boost::system::error_code ec;
      socket.read_some(boost::asio::buffer(request), ec);
      const std::string start = "HTTP/1.1 200 OK\r\nContent-Length: 100000\r\n\r\nabc";
      boost::asio::write(socket, boost::asio::buffer(start), ec);
      if (!close_mid_answer)
        while (!done) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    });
  }
  ~BrokenServer() {
    done = true;
    thread.join();
  }
  client::HttpUrl url() const { return client::HttpUrl{"127.0.0.1", acceptor.local_endpoint().port(), ""}; }

  boost::asio::io_context io;
  boost::asio::ip::tcp::acceptor acceptor;
  std::atomic<bool> done{false};
  std::thread thread;
};

std::string error_of(const client::HttpUrl& url, std::chrono::milliseconds deadline, double& seconds) {
  client::HttpOptions options;
  options.io_timeout = deadline;
  client::HttpConnection connection(url, options);
  const auto start = std::chrono::steady_clock::now();
  std::string what;
  try {
    connection.get("/models/x/base");
  } catch (const client::ConnectionError& e) {
    what = e.what();
  }
  seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return what;
}

TEST(Receiver, AServerThatStallsMidAnswerIsAnErrorWithinTheDeadline) {
  BrokenServer stalling(false);
  double seconds = 0;
  const std::string what = error_of(stalling.url(), std::chrono::milliseconds(300), seconds);
  EXPECT_NE(what.find("no progress within 300 ms"), std::string::npos) << what;
  EXPECT_NE(what.find("/models/x/base"), std::string::npos) << what;
  EXPECT_GE(seconds, 0.25);
  EXPECT_LT(seconds, 3.0);
}

TEST(Receiver, AServerThatClosesMidAnswerIsAClearError) {
  BrokenServer closing(true);
  double seconds = 0;
  const std::string what = error_of(closing.url(), std::chrono::milliseconds(5000), seconds);
  EXPECT_NE(what.find("closed the connection mid-answer"), std::string::npos) << what;
  EXPECT_LT(seconds, 3.0);
}

TEST(Receiver, AnUnknownModelIsACleanError) {
  Server server(terrain().catalogue);
  client::ReceiverClient client(server.url());
  try {
    client.open("nope");
    FAIL() << "opened an unknown model";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("no model named 'nope'"), std::string::npos) << e.what();
  }
}

TEST(Receiver, ServerUrlsParse) {
  const client::HttpUrl url = client::parse_http_url("http://example.org:8080/cdn/pm/");
  EXPECT_EQ(url.host, "example.org");
  EXPECT_EQ(url.port, 8080);
  EXPECT_EQ(url.prefix, "/cdn/pm");
  EXPECT_EQ(client::parse_http_url("http://h").port, 80);
  EXPECT_THROW(client::parse_http_url("https://h"), Error);
  EXPECT_THROW(client::parse_http_url("http://h:0"), Error);
  EXPECT_THROW(client::parse_http_url("http://h:12x"), Error);
  EXPECT_THROW(client::parse_http_url("http://h/p?q=1"), Error);
}

}  // namespace
}  // namespace pms
