// The session modes over the HTTP port's WebSocket (/ws): a flight in each of the four ends with the mesh and
// the payload bytes of the same flight over TCP, a session dropped with its server resumes on a new one, and the upgrade's
// refusals (Origin, not an upgrade, the sessions cap).
#include <gtest/gtest.h>
#include <atomic>
#include <memory>
#include <thread>

#include "client/streaming_client.h"
#include "client/websocket_link.h"
#include "http_test_client.h"
#include "protocol/message_types.h"
#include "protocol/stream_mode.h"
#include "server/http_server.h"
#include "streaming_fixture.h"
#include "test_support.h"
#include "ws_test_client.h"

namespace pms::test {
namespace {

const Fixture& terrain() { return terrain_fixture(20000, 3); }

server::WebOptions web_options(const server::ServerLimits& sessions = {}) {
  server::WebOptions web;
  web.sessions = sessions;
  return web;
}

struct WsServer {
  explicit WsServer(const server::WebOptions& web = web_options(), const server::HttpLimits& limits = {},
                    uint16_t port = 0)
      : http(terrain().catalogue, limits, "127.0.0.1", port, web) {
    http.start();
  }
  uint16_t port() const { return http.port(); }
  server::HttpServer http;
};

client::ClientOptions over_websocket(client::ClientOptions options) {
  options.websocket_path = "/ws";
  return options;
}

struct Flight {
  Faces faces;
  uint64_t payload_up = 0, payload_down = 0;
};

Flight fly(client::StreamingClient& client, const std::vector<Camera>& path) {
  client.open("terrain");
  for (const Camera& camera : path) client.frame(camera);
  const client::LinkCounters c = client.counters();
  return {faces_by_id(client.session().mesh()), c.payload_up(), c.payload_down()};
}

TEST(WebSocket, AFlightEqualsTheTcpFlightInMeshAndBytes) {
  const Fixture& f = terrain();
  const std::vector<Camera> path = orbit_path(f.hierarchy, 10, 0.7f);
  using enum protocol::StreamMode;
  for (const protocol::StreamMode mode : {sender_driven, view_independent, sender_plain, dag}) {
    SCOPED_TRACE(protocol::mode_name(mode));
    client::ClientOptions options{1.0f};
    options.mode = mode;
    LoopbackTcpServer tcp(f.catalogue);
    WsServer ws;
    client::StreamingClient over_tcp("127.0.0.1", tcp.port(), options);
    client::StreamingClient over_ws("127.0.0.1", ws.port(), over_websocket(options));
    const Flight a = fly(over_tcp, path);
    const Flight b = fly(over_ws, path);
    EXPECT_EQ(a.faces, b.faces);
    EXPECT_EQ(a.payload_up, b.payload_up);
    EXPECT_EQ(a.payload_down, b.payload_down);
    if (mode == protocol::StreamMode::sender_driven) {
      EXPECT_EQ(b.faces, local_faces(f.snapped, path.back(), 1.0f));
    }
    EXPECT_GT(ws.http.ws_sessions().bytes_out.load(), 0u);
    EXPECT_EQ(ws.http.ws_stats().upgrades.load(), 1u);
  }
}

TEST(WebSocket, AStreamCommandFliesOverIt) {
  EXPECT_EQ(client::parse_websocket_url("ws://127.0.0.1:8080/ws")->path, "/ws");
  EXPECT_EQ(client::parse_websocket_url("ws://host:81")->path, "/ws");
  EXPECT_EQ(client::parse_websocket_url("ws://host:81")->port, 81);
  EXPECT_FALSE(client::parse_websocket_url("http://host:81/ws"));
  EXPECT_FALSE(client::parse_websocket_url("ws://host/ws"));
}

TEST(WebSocket, ASessionResumesOnARestartedServer) {
  const Fixture& f = terrain();
  auto server = std::make_unique<WsServer>();
  const uint16_t port = server->port();
  const std::vector<Camera> path = orbit_path(f.hierarchy, 10, 1.1f);
  const size_t half = path.size() / 2;
  client::ClientOptions options = over_websocket(client::ClientOptions{0.5f});
  options.reconnect_attempts = 8;
  options.reconnect_delay = std::chrono::milliseconds(20);
  std::atomic<size_t> told{0};
  options.on_reconnect = [&](const std::string&, uint32_t) { ++told; };
  client::StreamingClient client("127.0.0.1", port, options);
  client.open("terrain");
  for (size_t i = 0; i < half; ++i) client.frame(path[i]);
  server.reset();  // drops the WebSocket
  std::thread restart([&] {
    while (told < 2) std::this_thread::sleep_for(std::chrono::milliseconds(2));
    server = std::make_unique<WsServer>(web_options(), server::HttpLimits{}, port);
  });
  client.frame(path[half]);
  restart.join();
  for (size_t i = half + 1; i < path.size(); ++i) client.frame(path[i]);
  EXPECT_GE(told.load(), 2u);
  EXPECT_EQ(faces_by_id(client.session().mesh()), local_faces(f.snapped, path.back(), 0.5f));
}

TEST(WebSocket, ASessionPaysItsAddressBudgetAndIsSlowedNotBroken) {
  const Fixture& f = terrain();
  server::HttpLimits limits;
  limits.address_budget = 4000;  // units a second: the flight costs more than the second's burst
  WsServer server(web_options(), limits);
  const std::vector<Camera> path = orbit_path(f.hierarchy, 6, 0.2f);
  client::StreamingClient client("127.0.0.1", server.port(), over_websocket(client::ClientOptions{1.0f}));
  const Flight flight = fly(client, path);
  EXPECT_EQ(flight.faces, local_faces(f.snapped, path.back(), 1.0f));
  EXPECT_GT(server.http.ws_stats().budget_waits.load(), 0u);
  EXPECT_GT(server.http.tracked_addresses(), 0u);
}

TEST(WebSocket, TheUpgradeChecksTheOrigin) {
  server::WebOptions listed = web_options();
  listed.allowed_origins = {"https://viewer.example"};
  WsServer same, other(listed);
  const std::string self = "http://127.0.0.1:" + std::to_string(same.port());
  EXPECT_EQ(upgrade_status(same.port(), {{"Origin", self}}), 101);
  EXPECT_EQ(upgrade_status(same.port(), {{"Origin", "http://evil.example"}}), 403);
  EXPECT_EQ(upgrade_status(same.port(), {}), 101);  // no Origin: not a browser
  EXPECT_EQ(upgrade_status(other.port(), {{"Origin", "https://viewer.example"}}), 101);
  EXPECT_EQ(upgrade_status(other.port(), {{"Origin", "http://127.0.0.1:" + std::to_string(other.port())}}), 403);
  EXPECT_EQ(same.http.ws_stats().refused_origin.load(), 1u);
  EXPECT_THROW(WsTestClient(same.port(), "http://evil.example"), std::exception);
}

TEST(WebSocket, WhatIsNoUpgradeIsRefused) {
  WsServer server;
  EXPECT_EQ(upgrade_status(server.port(), {{"Upgrade", ""}}), 426);
  EXPECT_EQ(upgrade_status(server.port(), {{"Sec-WebSocket-Version", "8"}}), 426);
  EXPECT_EQ(upgrade_status(server.port(), {{"Sec-WebSocket-Key", ""}}), 400);
  HttpTestClient plain(server.port());
  EXPECT_EQ(plain.get("/ws").status, 426);
  EXPECT_EQ(plain.get("/models").status, 200);  // the connection goes on
}

TEST(WebSocket, TheSessionsCapAnswers503) {
  server::ServerLimits sessions;
  sessions.max_sessions = 2;
  WsServer server(web_options(sessions));
  WsTestClient a(server.port()), b(server.port());
  EXPECT_EQ(upgrade_status(server.port(), {}), 503);
  EXPECT_EQ(server.http.ws_stats().refused_full.load(), 1u);
}

}  // namespace
}  // namespace pms::test
