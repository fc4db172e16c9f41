// Hostile WebSocket peers on the HTTP port, each while a good WebSocket client flies: silent and slow
// peers, floods of messages, of pings and of tiny fragments, text, malformed and oversize messages, many
// connections from one address and from others (127.0.0.2..). Each attacker ends alone; the good flight
// ends with the mesh local refinement gives.
#include <gtest/gtest.h>
#include <atomic>
#include <functional>
#include <memory>
#include <thread>

#include "client/streaming_client.h"
#include "protocol/client_messages.h"
#include "protocol/framing.h"
#include "protocol/message_types.h"
#include "server/http_server.h"
#include "streaming_fixture.h"
#include "test_support.h"
#include "ws_test_client.h"

namespace pms::test {
namespace {

using protocol::ErrorCode;

const Fixture& terrain() { return terrain_fixture(20000, 3); }

// Short deadlines, so each attack ends within the test, yet long enough for the good client on a loaded
// machine (a sanitizer build, other tests beside it).
server::WebOptions tight() {
  server::WebOptions web;
  web.sessions.handshake_timeout_ms = 1000;
  web.sessions.frame_timeout_ms = 500;
  web.sessions.write_timeout_ms = 800;
  web.sessions.idle_timeout_ms = 3000;
  web.sessions.max_client_message = 64u << 10;
  web.sessions.max_message_rate = 200;
  return web;
}

struct Server {
  explicit Server(const server::WebOptions& web = tight(), const server::HttpLimits& limits = {})
      : http(terrain().catalogue, limits, "127.0.0.1", 0, web) {
    http.start();
  }
  uint16_t port() const { return http.port(); }
  server::HttpServer http;
};

// A good client's flight over the WebSocket, beside `attack`; the flight must end where local refinement does.
void fly_beside(const Server& server, const std::function<void()>& attack) {
  const Fixture& f = terrain();
  const std::vector<Camera> path = orbit_path(f.hierarchy, 8, 0.4f);
  std::atomic<bool> done{false};
  Faces faces;
  std::thread good([&] {
    client::ClientOptions options{1.0f};
    options.websocket_path = "/ws";
    client::StreamingClient client("127.0.0.1", server.port(), options);
    client.open("terrain");
    for (const Camera& camera : path) client.frame(camera);
    faces = faces_by_id(client.session().mesh());
    done = true;
  });
  attack();
  good.join();
  ASSERT_TRUE(done);
  EXPECT_EQ(faces, local_faces(f.snapped, path.back(), 1.0f));
}

std::vector<uint8_t> hello() { return protocol::encode(protocol::Hello{protocol::kProtocolVersion, "attacker"}); }

TEST(WsAttack, ASilentPeerIsClosedAtTheHandshakeDeadline) {
  Server server;
  fly_beside(server, [&] {
    WsTestClient silent(server.port());
    std::optional<ErrorCode> error;
    EXPECT_TRUE(silent.closed_by_server(&error));
    EXPECT_EQ(error, ErrorCode::timeout);
  });
  EXPECT_GE(server.http.ws_sessions().sessions_timed_out.load(), 1u);
}

TEST(WsAttack, AMessageBegunMustComplete) {
  Server server;
  fly_beside(server, [&] {
    WsTestClient slow(server.port());
    const std::vector<uint8_t> frame = hello();
    std::vector<uint8_t> piece = ws_frame(2, false, {frame.begin(), frame.begin() + 3});
    slow.send_raw(piece);  // the message's first fragment, and never the rest
    std::optional<ErrorCode> error;
    EXPECT_TRUE(slow.closed_by_server(&error));
    EXPECT_EQ(error, ErrorCode::timeout);
  });
}

TEST(WsAttack, TextAndMisframedMessagesEndTheirSession) {
  Server server;
  fly_beside(server, [&] {
    WsTestClient text(server.port());
    text.send_text("HELLO");
    std::optional<ErrorCode> error;
    EXPECT_TRUE(text.closed_by_server(&error));
    EXPECT_EQ(error, ErrorCode::bad_message);

    WsTestClient two(server.port());
    std::vector<uint8_t> both = hello();
    const std::vector<uint8_t> second = hello();
    both.insert(both.end(), second.begin(), second.end());
    two.send_binary(both);
    error.reset();
    EXPECT_TRUE(two.closed_by_server(&error));
    EXPECT_EQ(error, ErrorCode::bad_message);

    WsTestClient half(server.port());
    const std::vector<uint8_t> frame = hello();
    half.send_binary({frame.begin(), frame.end() - 1});
    error.reset();
    EXPECT_TRUE(half.closed_by_server(&error));
    EXPECT_EQ(error, ErrorCode::bad_message);

    WsTestClient junk(server.port());
    junk.send_binary(std::vector<uint8_t>(64, 0xFF));
    EXPECT_TRUE(junk.closed_by_server());

    WsTestClient broken(server.port());
    broken.send_raw({0x8F, 0x80, 0, 0, 0, 0});  // a reserved opcode: not a WebSocket frame
    EXPECT_TRUE(broken.closed_by_server());
  });
  EXPECT_GE(server.http.ws_stats().messages_refused.load(), 3u);
}

TEST(WsAttack, OversizeMessagesAreRefused) {
  Server server;
  fly_beside(server, [&] {
    WsTestClient big(server.port());
    big.send_raw(ws_frame(2, true, std::vector<uint8_t>(size_t(tight().sessions.max_client_message) + 64, 0)));
    EXPECT_TRUE(big.closed_by_server());
  });
}

TEST(WsAttack, FloodsOfMessagesPingsAndTinyFragmentsEndOnlyTheirSession) {
  Server server;
  fly_beside(server, [&] {
    WsTestClient fragments(server.port());
    // The header of a frame of 8000 bytes (a LIST's type: it is never decoded), then the frame a byte a
    // fragment, after a run of empty fragments.
    std::vector<uint8_t> flood = ws_frame(2, false, {0x40, 0x1F, 0, 0, uint8_t(protocol::MessageType::list)});
    for (int i = 0; i < 5000; ++i) {
      const std::vector<uint8_t> piece = ws_frame(0, false, {});
      flood.insert(flood.end(), piece.begin(), piece.end());
    }
    for (int i = 0; i < 5000; ++i) {
      const std::vector<uint8_t> piece = ws_frame(0, false, {0});
      flood.insert(flood.end(), piece.begin(), piece.end());
    }
    fragments.send_raw(flood);
    EXPECT_TRUE(fragments.closed_by_server());
    EXPECT_EQ(server.http.ws_stats().messages_refused.load(), 1u) << "the fragments";

    WsTestClient pings(server.port());
    std::vector<uint8_t> many;
    for (int i = 0; i < 2000; ++i) {
      const std::vector<uint8_t> ping = ws_frame(9, true, {1, 2, 3});
      many.insert(many.end(), ping.begin(), ping.end());
    }
    pings.send_raw(many);
    std::optional<ErrorCode> error;
    EXPECT_TRUE(pings.closed_by_server(&error));

    EXPECT_EQ(error, ErrorCode::bad_message);
    EXPECT_EQ(server.http.ws_stats().messages_refused.load(), 2u) << "the pings";

    // LIST over and over: the rate holds it back, so its answers come at the rate, not at once.
    WsTestClient lists(server.port());
    lists.send_binary(hello());
    for (int i = 0; i < 1000; ++i) lists.send_binary(protocol::encode(protocol::List{}));
    EXPECT_TRUE(lists.read().has_value());  // HELLO_OK: the session goes on
  });
}

TEST(WsAttack, APeerThatStopsReadingIsReset) {
  server::WebOptions web = tight();
  web.sessions.max_message_rate = 0;  // the answers pile up as fast as the LISTs come
  Server server(web);
  fly_beside(server, [&] {
    WsTestClient deaf(server.port(), "", "127.0.0.1", 5000, 4096);
    std::vector<uint8_t> flood = ws_frame(2, true, hello());
    const std::vector<uint8_t> list = ws_frame(2, true, protocol::encode(protocol::List{}));
    for (int i = 0; i < 40000; ++i) flood.insert(flood.end(), list.begin(), list.end());
    // The server stops reading once its queue is full (the kernels' buffers take the rest of the flood),
    // and resets the peer at the write deadline: a counter looked at until then, nothing read.
    deaf.send_raw(flood);
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    while (server.http.ws_sessions().sessions_timed_out.load() == 0 && std::chrono::steady_clock::now() < until)
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    EXPECT_EQ(server.http.ws_sessions().sessions_timed_out.load(), 1u);
    EXPECT_FALSE(deaf.send_raw(list)) << "the peer was reset";
  });
}

TEST(WsAttack, ManyConnectionsFromOneAddressAndFromOthers) {
  server::HttpLimits limits;
  limits.max_connections_per_address = 6;  // the good client's and a few more
  Server server(tight(), limits);
  fly_beside(server, [&] {
    std::vector<std::unique_ptr<WsTestClient>> held;
    int refused = 0;
    for (int i = 0; i < 12; ++i) {
      try {
        held.push_back(std::make_unique<WsTestClient>(server.port(), "", "127.0.0.3"));
      } catch (const std::exception&) {
        ++refused;
      }
    }
    EXPECT_EQ(held.size(), 6u);
    EXPECT_EQ(refused, 6);
    for (int a = 4; a < 8; ++a) {  // every other address still gets its own
      const std::string from = "127.0.0." + std::to_string(a);
      EXPECT_NO_THROW(WsTestClient(server.port(), "", from)) << from;
    }
  });
  EXPECT_GE(server.http.stats().connections_refused_per_address.load(), 6u);
}

}  // namespace
}  // namespace pms::test
