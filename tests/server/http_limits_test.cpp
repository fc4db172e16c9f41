// What one client of the HTTP transport may take, over real loopback connections from several loopback
// addresses: connections per address, the work budgets (a client over them waits, it is not refused), a
// trusted proxy's X-Forwarded-For, turns bounded in time with large answers built over several, and a peer
// that never reads reset at the write deadline although every write succeeded.
#include <gtest/gtest.h>
#include <atomic>
#include <chrono>
#include <memory>
#include <thread>

#include "http_test_client.h"
#include "protocol/base64url.h"
#include "protocol/split_request.h"
#include "server/http_cost.h"
#include "server/http_server.h"
#include "server/limits.h"
#include "streaming_fixture.h"

namespace pms::test {
namespace {

using protocol::SplitRequest;
using server::HttpLimits;
using Clock = std::chrono::steady_clock;

const Fixture& terrain() { return terrain_fixture(20000, 3); }

struct Server : LoopbackHttpServer {
  explicit Server(const HttpLimits& limits) : LoopbackHttpServer(terrain().catalogue, limits) {}
  const server::HttpStats& stats() const { return http.stats(); }
};

// Every root that has a split, with `depth` levels of descendants: the most one request code names here.
std::string all_roots_url(uint32_t depth) {
  const ModelData& model = terrain().catalogue->find("terrain")->model();
  SplitRequest request{depth, {}};
  for (uint32_t r = 0; r < model.root_count; ++r)
    if (!model.is_leaf(r)) request.ids.push_back(model.id(r));
  return model_url(*terrain().catalogue, "terrain") + "/splits/" + protocol::base64url_encode(protocol::encode_split_request(request));
}

// What the request of all_roots_url(3) costs (http_cost.h), as a server without budgets counts it.
double expensive_cost() {
  static const double cost = [] {
    Server probe(HttpLimits{});
    HttpTestClient client(probe.port());
    const std::string url = all_roots_url(3);
    const HttpReply reply = client.get(url);
    EXPECT_EQ(reply.status, 200);
    const size_t request_bytes = ("GET " + url + " HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n").size();
    return server::request_cost(probe.stats().splits_served.load(), reply.body.size(), request_bytes);
  }();
  return cost;
}

// Counters move on the server's threads, after what a peer sees: poll them under a deadline.
bool reaches(const std::atomic<uint64_t>& counter, uint64_t value, std::chrono::milliseconds within) {
  const Clock::time_point deadline = Clock::now() + within;
  while (counter.load() < value && Clock::now() < deadline) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  return counter.load() >= value;
}

TEST(HttpLimits, OneAddressOverItsConnectionCapGets503WhileAnotherIsServed) {
  HttpLimits limits;
  limits.max_connections_per_address = 4;
  Server server(limits);
  std::vector<std::unique_ptr<HttpTestClient>> held;
  for (int i = 0; i < 4; ++i) {
    held.push_back(std::make_unique<HttpTestClient>(server.port(), 5000, "127.0.0.2"));
    ASSERT_EQ(held.back()->get("/models").status, 200);
  }
  HttpTestClient over(server.port(), 5000, "127.0.0.2");
  const HttpReply refused = over.read();
  EXPECT_EQ(refused.status, 503);
  EXPECT_EQ(refused.header("retry-after"), "1");
  EXPECT_TRUE(over.closed_by_server());
  EXPECT_EQ(server.stats().connections_refused_per_address.load(), 1u);
  // Another address is not affected; the capped one gets its slot back when a connection ends.
  HttpTestClient other(server.port(), 5000, "127.0.0.3");
  EXPECT_EQ(other.get("/models").status, 200);
  held.pop_back();
  ASSERT_TRUE(reaches(server.stats().connections_opened, 5, std::chrono::milliseconds(100)));
  const Clock::time_point deadline = Clock::now() + std::chrono::seconds(5);
  bool admitted = false;
  while (!admitted && Clock::now() < deadline) {  // the server sees the close a moment after the client
    HttpTestClient again(server.port(), 5000, "127.0.0.2");
    admitted = again.get("/models").status == 200;
  }
  EXPECT_TRUE(admitted);
}

TEST(HttpLimits, ATrustedProxyIsNotCappedAndItsClientsAreChargedApart) {
  HttpLimits limits;
  limits.max_connections_per_address = 2;
  limits.address_budget = uint32_t(2 * expensive_cost());  // two of the expensive requests below
  limits.connection_budget = 0;
  limits.trusted_proxies = server::AddressRanges::parse({"127.0.0.4/32"}, "--trusted-proxy");
  Server server(limits);
  std::vector<std::unique_ptr<HttpTestClient>> proxy;
  for (int i = 0; i < 5; ++i) {
    proxy.push_back(std::make_unique<HttpTestClient>(server.port(), 10000, "127.0.0.4"));
    ASSERT_EQ(proxy.back()->get("/models").status, 200) << "a trusted proxy's connection " << i;
  }
  EXPECT_EQ(server.stats().connections_refused_per_address.load(), 0u);
  // One forwarded client asks much more than its budget: slowed, never refused.
  const std::string expensive = all_roots_url(3);
  for (int i = 0; i < 4; ++i)
    ASSERT_EQ(proxy[0]->get(expensive, {{"X-Forwarded-For", "198.51.100.7"}}).status, 200);
  EXPECT_GT(server.stats().budget_waits.load(), 0u);
  // That client now owes about one request: a second one charged to its address would wait half a second
  // before its next. Another client behind the same proxy has its own budget, and a forged hop before the
  // proxy's own entry is not believed (the rightmost untrusted entry is the client): its two requests go
  // through at once.
  const Clock::time_point start = Clock::now();
  for (int i = 0; i < 2; ++i)
    ASSERT_EQ(proxy[1]->get(expensive, {{"X-Forwarded-For", "198.51.100.7, 203.0.113.9"}}).status, 200);
  EXPECT_LT(std::chrono::duration<double>(Clock::now() - start).count(), 0.45);
  EXPECT_GE(server.http.tracked_addresses(), 2u);
}

TEST(HttpLimits, AClientOverItsBudgetWaitsAndIsAnswered) {
  HttpLimits limits;
  limits.address_budget = 0;
  limits.connection_budget = uint32_t(2 * expensive_cost());  // two a second, after a burst of two
  Server server(limits);
  HttpTestClient client(server.port(), 20000);
  const std::string expensive = all_roots_url(3);
  const HttpReply first = client.get(expensive);
  ASSERT_EQ(first.status, 200);
  const Clock::time_point start = Clock::now();
  for (int i = 0; i < 5; ++i) {
    const HttpReply again = client.get(expensive);
    ASSERT_EQ(again.status, 200);
    ASSERT_EQ(again.body, first.body);
  }
  // Charged after its answer: the five before the last ran three requests' worth past the two lent, and
  // that debt was repaid, two a second, before the last one was read.
  EXPECT_GT(server.stats().budget_waits.load(), 0u);
  EXPECT_GE(std::chrono::duration<double>(Clock::now() - start).count(), 1.4);
}

TEST(HttpLimits, ALargeAnswerIsBuiltOverTurnsAndIsTheSameAnswer) {
  HttpLimits sliced_limits;
  sliced_limits.turn_us = 1;  // every answer of more than a few ids takes several turns
  Server sliced(sliced_limits), whole(HttpLimits{});
  HttpTestClient a(sliced.port()), b(whole.port());
  for (uint32_t depth : {0u, 2u, 5u}) {
    const std::string url = all_roots_url(depth);
    const HttpReply x = a.get(url), y = b.get(url);
    ASSERT_EQ(x.status, 200);
    EXPECT_EQ(x.headers, y.headers) << "depth " << depth;
    EXPECT_EQ(x.body, y.body) << "depth " << depth;
  }
  EXPECT_GT(sliced.stats().sliced_answers.load(), 0u);
  EXPECT_GT(sliced.stats().longest_turn_us.load(), 0u);
}

// Answers that fit the kernel's buffers: every write succeeds, and only the bytes the kernel still holds
// tell the server the peer is not reading.
TEST(HttpLimits, APipeliningPeerThatNeverReadsIsResetAtTheWriteDeadline) {
  HttpLimits limits;
  limits.write_timeout_ms = 300;
  limits.idle_timeout_ms = 60000;
  Server server(limits);
  HttpTestClient reader(server.port(), 5000, "127.0.0.5", 4096);
  std::string requests;
  const std::string base = model_url(*terrain().catalogue, "terrain") + "/base";
  for (int i = 0; i < 40; ++i) requests += "GET " + base + " HTTP/1.1\r\nHost: x\r\n\r\n";
  reader.send(requests);
  ASSERT_TRUE(reaches(server.stats().requests, 40, std::chrono::milliseconds(5000)));
  EXPECT_TRUE(reaches(server.stats().connections_reset, 1, std::chrono::milliseconds(5000)))
      << "held past the write deadline";
  EXPECT_EQ(server.stats().connections_active.load(), 0u);
}

}  // namespace
}  // namespace pms::test
