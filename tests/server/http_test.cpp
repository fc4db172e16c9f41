// The receiver-driven HTTP transport over real loopback connections: every route, the cache headers, 304s,
// keep-alive, hostile requests answered with 4xx while a good client goes on, deadlines, the connection cap.
#include <gtest/gtest.h>
#include <atomic>
#include <chrono>
#include <memory>
#include <nlohmann/json.hpp>
#include <thread>

#include "common/bit_stream.h"
#include "http_test_client.h"
#include "io/shapes.h"
#include "protocol/base64url.h"
#include "protocol/message_types.h"
#include "protocol/server_messages.h"
#include "protocol/split_bands.h"
#include "protocol/split_request.h"
#include "server/http_server.h"
#include "server/limits.h"
#include "spm/hierarchy.h"
#include "spm/refine_info.h"
#include "spm/split_codec.h"
#include "spm/vertex_hierarchy.h"
#include "streaming_fixture.h"

namespace pms::test {
namespace {

using protocol::SplitRequest;
using server::HttpLimits;
using server::HttpServer;

const Fixture& terrain() {
  return terrain_fixture(20000, 3);
}

struct Server : LoopbackHttpServer {
  explicit Server(const HttpLimits& limits = {}) : LoopbackHttpServer(terrain().catalogue, limits) {}
};

const server::ServedModel& served() { return *terrain().catalogue->find("terrain"); }

// /models/terrain/VERSION: where the model's resources are.
std::string at() { return model_url(*terrain().catalogue, "terrain"); }

// The first `n` roots that have a split, as one request.
SplitRequest some_roots(size_t n, uint32_t depth = 0) {
  const ModelData& model = served().model();
  SplitRequest request{depth, {}};
  for (uint32_t r = 0; r < model.root_count && request.ids.size() < n; ++r)
    if (!model.is_leaf(r)) request.ids.push_back(model.id(r));
  return request;
}

std::string splits_url(const SplitRequest& request) {
  return at() + "/splits/" + protocol::base64url_encode(protocol::encode_split_request(request));
}

// The splits an answer to `request` carries, in its order, read as a client that holds the base mesh
// reads them (records format 4: the bands need the client's hierarchy to decode).
std::vector<VertexId> split_ids(const std::vector<uint8_t>& body, const SplitRequest& request) {
  EXPECT_EQ(served().records_format, 4u);
  const std::vector<uint8_t>& frame = *served().base_frame;
  const protocol::Base base = protocol::decode_base(std::span(frame).subspan(protocol::kFrameHeaderBytes));
  VertexHierarchy h;
  for (uint32_t r = 0; r < base.root_count(); ++r)
    h.add_root(VertexId{r, 1}, &base.positions[3 * size_t(r)], base.refine[r]);
  const uint32_t before = h.size();
  protocol::read_split_bands(body, request, served().file->split_codec(), served().context.grid, h, 1u << 20);
  std::vector<VertexId> ids;
  for (uint32_t slot = before; slot < h.size(); slot += 2)
    ids.push_back(h.id(h.parent(slot)));  // two children per split
  return ids;
}

// A deadline closes the socket before the handler that counts it runs: counters lag what a peer sees.
bool reaches(const std::atomic<uint64_t>& counter, uint64_t value) {
  for (int i = 0; i < 200 && counter.load() < value; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  return counter.load() == value;
}

// Only what a cache needs: every byte of a header is paid per request (docs/internals.md, "Receiver-driven
// bench").
void expect_cacheable(const HttpReply& reply) {
  EXPECT_EQ(reply.header("cache-control"), "max-age=31536000, immutable");
  const std::string etag = reply.header("etag");
  ASSERT_EQ(etag.size(), 13u);  // strong: quoted, 64 bits in base64url
  EXPECT_EQ(etag.front(), '"');
  EXPECT_EQ(etag.back(), '"');
  EXPECT_EQ(etag.find_first_not_of("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789-_", 1), 12u);
  std::vector<std::string> names;
  for (const auto& [name, value] : reply.headers) names.push_back(name);
  if (reply.status == 304)  // the headers a 200 would carry that RFC 9110 §15.4.5 asks for
    EXPECT_EQ(names, (std::vector<std::string>{"cache-control", "etag"}));
  else EXPECT_EQ(names, (std::vector<std::string>{"cache-control", "content-length", "content-type", "etag"}));
}

TEST(Http, CatalogueAndBaseAreCacheableAndTheSameForEveryClient) {
  Server server;
  HttpTestClient a(server.port()), b(server.port());
  const HttpReply models = a.get("/models");
  ASSERT_EQ(models.status, 200);
  EXPECT_EQ(models.header("content-type"), "application/json");
  const auto json = nlohmann::json::parse(models.text());
  EXPECT_EQ(json["models"][0]["name"], "terrain");
  EXPECT_EQ(json["models"][0]["vsplits"], served().info.vsplits);
  const HttpReply base = a.get(at() + "/base");
  ASSERT_EQ(base.status, 200);
  expect_cacheable(base);
  const std::vector<uint8_t>& frame = *served().base_frame;
  EXPECT_EQ(base.body, std::vector<uint8_t>(frame.begin() + protocol::kFrameHeaderBytes, frame.end()));
  EXPECT_EQ(protocol::decode_base(base.body).positions.size(), 3 * size_t(served().model().root_count));
  const HttpReply again = b.get(at() + "/base");  // another client, another connection
  EXPECT_EQ(again.header("etag"), base.header("etag"));
  EXPECT_EQ(again.headers, base.headers);
  EXPECT_EQ(again.body, base.body);
  const HttpReply head = b.head(at() + "/base");
  EXPECT_EQ(head.status, 200);
  EXPECT_EQ(head.header("content-length"), std::to_string(base.body.size()));
  EXPECT_TRUE(head.body.empty());
}

// The catalogue names each model's version and changes with the model set: a cache may keep it for
// max-age, then revalidates it for a 304. Every other URL carries the version: another one is gone (410,
// with the entry of the version served), none at all is no resource.
TEST(Http, TheCatalogueIsRevalidatedAndAnotherVersionIsGone) {
  HttpLimits limits;
  limits.catalogue_max_age_s = 7;
  Server server(limits);
  HttpTestClient client(server.port());
  const HttpReply models = client.get("/models");
  EXPECT_EQ(models.header("cache-control"), "max-age=7");
  const auto entry = nlohmann::json::parse(models.text())["models"][0];
  EXPECT_EQ(entry["version"], served().version);
  EXPECT_EQ(at(), "/models/terrain/" + served().version);
  const HttpReply again = client.get("/models", {{"If-None-Match", models.header("etag")}});
  EXPECT_EQ(again.status, 304);
  EXPECT_TRUE(again.body.empty());
  std::string old = served().version;
  old[0] = old[0] == '0' ? '1' : '0';
  for (const std::string resource : {"/base", "/codec", "/blocks/0/1/2", "/head", "/levels/0"}) {
    const HttpReply gone = client.get("/models/terrain/" + old + resource);
    EXPECT_EQ(gone.status, 410) << resource;
    EXPECT_EQ(gone.header("cache-control"), "no-store");
    EXPECT_EQ(gone.header("content-type"), "application/json");
    const auto body = nlohmann::json::parse(gone.text());
    EXPECT_EQ(body["model"], entry) << "the entry GET /models has";
    EXPECT_NE(body["error"].get<std::string>().find(served().version), std::string::npos);
  }
  EXPECT_EQ(client.get("/models/terrain/base").status, 404);
  EXPECT_EQ(client.get("/models/terrain/" + served().version).status, 404);  // a version, no resource
  std::string upper = served().version;
  for (char& c : upper) c = char(std::toupper(c));
  if (upper != served().version) {  // one spelling per version: no second URL for its bytes
    EXPECT_EQ(client.get("/models/terrain/" + upper + "/base").status, 404);
  }
}

// Stateless: another server process over the same file answers every URL with the same headers and bytes.
TEST(Http, TwoServersOfOneFileAnswerAlike) {
  Server first;
  HttpServer second(server::Catalogue::open({terrain().path}), HttpLimits{}, "127.0.0.1", 0);
  second.start();
  HttpTestClient a(first.port()), b(second.port());
  for (const std::string& url :
       {std::string("/models"), at() + "/base", splits_url(some_roots(7, 2)),
        at() + "/blocks/" + std::to_string(some_roots(1).ids[0].tree) + "/1/3"}) {
    const HttpReply x = a.get(url), y = b.get(url);
    ASSERT_EQ(x.status, 200) << url << ": " << x.text();
    EXPECT_EQ(x.headers, y.headers) << url;
    EXPECT_EQ(x.body, y.body) << url;
  }
  EXPECT_NE(a.get(at() + "/base").header("etag"), a.get(splits_url(some_roots(7, 2))).header("etag"));
}

TEST(Http, IfNoneMatchGetsA304WithoutABody) {
  Server server;
  HttpTestClient client(server.port());
  const std::string url = splits_url(some_roots(5));
  const HttpReply first = client.get(url);
  ASSERT_EQ(first.status, 200);
  const HttpReply cached = client.get(url, {{"If-None-Match", "\"0000\", " + first.header("etag")}});
  EXPECT_EQ(cached.status, 304);
  EXPECT_TRUE(cached.body.empty());
  EXPECT_EQ(cached.header("etag"), first.header("etag"));
  expect_cacheable(cached);
  EXPECT_EQ(client.get(url, {{"If-None-Match", "\"other\""}}).status, 200);
  EXPECT_EQ(server.http.stats().not_modified.load(), 1u);
}

TEST(Http, GetAndPostOfARequestCarryItsSplitsInCodeOrder) {
  Server server;
  HttpTestClient client(server.port());
  const SplitRequest request = some_roots(20);
  const HttpReply get = client.get(splits_url(request));
  ASSERT_EQ(get.status, 200) << get.text();
  expect_cacheable(get);
  EXPECT_EQ(split_ids(get.body, request), request.ids);  // the roots come in tree order
  const HttpReply post = client.post(at() + "/splits", protocol::encode_split_request(request));
  ASSERT_EQ(post.status, 200);
  EXPECT_EQ(post.body, get.body);
  EXPECT_EQ(post.header("etag"), get.header("etag"));  // one resource, whichever form named it
}

// Profiled (serve --profile-phases), the receiver-driven answers' time lands in the phases cheng-ooi's
// Table 1 names for a receiver-driven sender, never in the sender-driven ones; unprofiled, nothing is timed.
TEST(Http, ProfiledPhasesTimeTheReceiverDrivenAnswersOnly) {
  const SplitRequest request = some_roots(20, 2);
  const auto serve = [&](bool profile) {
    HttpLimits limits;
    limits.profile_phases = profile;
    auto server = std::make_unique<Server>(limits);
    HttpTestClient client(server->port());
    EXPECT_EQ(client.get(at() + "/base").status, 200);
    EXPECT_EQ(client.get(splits_url(request)).status, 200);
    EXPECT_TRUE(reaches(server->http.stats().requests, 2));
    return server;
  };
  const auto profiled = serve(true);
  const auto& ns = profiled->http.stats().phases.ns;
  EXPECT_GT(ns[size_t(server::Phase::send_base)].load(), 0u);
  EXPECT_GT(ns[size_t(server::Phase::decode_ids)].load(), 0u);
  EXPECT_GT(ns[size_t(server::Phase::search_splits)].load(), 0u);
  EXPECT_EQ(ns[size_t(server::Phase::determine_visibility)].load(), 0u) << "the client ranks, not the server";
  EXPECT_EQ(ns[size_t(server::Phase::update_front)].load(), 0u) << "a receiver-driven server holds no front";
  const auto plain = serve(false);
  for (const auto& phase : plain->http.stats().phases.ns) EXPECT_EQ(phase.load(), 0u);
}

TEST(Http, ADepthBringsDescendantsBreadthFirstAndBlocksTileTheTrees) {
  Server server;
  HttpTestClient client(server.port());
  const ModelData& model = served().model();
  const SplitRequest request = some_roots(1, 1);
  const uint32_t root = request.ids[0].tree;
  std::vector<VertexId> expected{model.id(root)};
  for (uint32_t c = 0; c < 2; ++c)
    if (!model.is_leaf(model.first_child[root] + c)) expected.push_back(model.id(model.first_child[root] + c));
  const HttpReply deep = client.get(splits_url(request));
  ASSERT_EQ(deep.status, 200);
  EXPECT_EQ(split_ids(deep.body, request), expected);
  const std::string block = at() + "/blocks/" + std::to_string(root) + "/1/1";
  const HttpReply tile = client.get(block);
  ASSERT_EQ(tile.status, 200) << tile.text();
  expect_cacheable(tile);
  EXPECT_EQ(tile.body, deep.body);
  // Blocks of depth 1 start at even depths only; node 2 is at depth 1.
  EXPECT_EQ(client.get(at() + "/blocks/" + std::to_string(root) + "/2/1").status, 400);
  EXPECT_EQ(client.get(at() + "/blocks/" + std::to_string(root) + "/01/1").status, 400);
}

// Both record forms from the one .pms (docs/protocol.md, "The plain form"): the plain form's URLs mirror
// the records' under /plain, with their own bytes and ETags, and the catalogue says the form is there.
TEST(Http, ThePlainFormIsServedBesideTheInfoFormWithItsOwnETags) {
  Server server;
  HttpTestClient client(server.port());
  const auto json = nlohmann::json::parse(client.get("/models").text());
  EXPECT_EQ(json["models"][0]["record_forms"], nlohmann::json::array({"info", "plain"}));
  const SplitRequest request = some_roots(20, 1);
  const std::string code = protocol::base64url_encode(protocol::encode_split_request(request));
  const uint32_t root = request.ids[0].tree;
  const std::string block = "/blocks/" + std::to_string(root) + "/1/2";
  for (const std::string& resource : {std::string("/codec"), "/splits/" + code, block}) {
    const HttpReply info = client.get(at() + resource);
    const HttpReply plain = client.get(at() + "/plain" + resource);
    ASSERT_EQ(info.status, 200) << resource;
    ASSERT_EQ(plain.status, 200) << resource << ": " << plain.text();
    expect_cacheable(plain);
    EXPECT_NE(plain.header("etag"), info.header("etag")) << resource;
    EXPECT_LT(plain.body.size(), info.body.size()) << resource << ": no refinement info";
    const HttpReply again = HttpTestClient(server.port()).get(at() + "/plain" + resource);
    EXPECT_EQ(again.body, plain.body);
    EXPECT_EQ(again.header("etag"), plain.header("etag"));
    EXPECT_EQ(client.get(at() + "/plain" + resource, {{"If-None-Match", plain.header("etag")}}).status, 304);
  }
  const HttpReply post = client.post(at() + "/plain/splits", protocol::encode_split_request(request));
  ASSERT_EQ(post.status, 200);
  EXPECT_EQ(post.body, client.get(at() + "/plain/splits/" + code).body);
  // Read as the area client reads them: the plain codec from /plain/codec, the splits of the request.
  const HttpReply tables = client.get(at() + "/plain/codec");
  BitReader r(tables.body, "plain tables");
  const SplitCodec codec = SplitCodec::deserialize(r);
  EXPECT_EQ(codec.form(), RecordForm::plain);
  const protocol::Base base = protocol::decode_base(client.get(at() + "/base").body);
  VertexHierarchy h;
  for (uint32_t t = 0; t < base.root_count(); ++t)
    h.add_root(VertexId{t, 1}, &base.positions[3 * size_t(t)],
               never_refines(base.refine[t]) ? base.refine[t] : plain_split_info());
  EXPECT_EQ(protocol::read_split_bands(post.body, request, codec, served().context.grid, h, 1u << 20),
            split_ids(client.get(splits_url(request)).body, request).size());
}

TEST(Http, BadPlainFormRequestsGetA4xx) {
  Server server;
  HttpTestClient bad(server.port());
  const ModelData& model = served().model();
  uint32_t leaf = 0;
  while (!model.is_leaf(leaf)) ++leaf;
  const auto plain_splits = [](const SplitRequest& request) {
    return at() + "/plain/splits/" + protocol::base64url_encode(protocol::encode_split_request(request));
  };
  EXPECT_EQ(bad.get(plain_splits({0, {model.id(leaf)}})).status, 404);         // a leaf: no split
  EXPECT_EQ(bad.get(plain_splits({0, {{model.root_count, 1}}})).status, 404);  // no such tree
  EXPECT_EQ(bad.get(plain_splits({99, {model.id(0)}})).status, 400);           // depth over the limit
  EXPECT_EQ(bad.get(at() + "/plain/splits/AA+A").status, 400);                 // not base64url
  EXPECT_EQ(bad.post(at() + "/plain/splits", std::vector<uint8_t>(10, 0)).status, 400);
  EXPECT_EQ(bad.get(at() + "/plain/blocks/0/2/1").status, 400);   // an unaligned block
  EXPECT_EQ(bad.get(at() + "/plain/blocks/0/01/1").status, 400);  // not plain decimal
  EXPECT_EQ(bad.get(at() + "/plain/blocks/" + std::to_string(model.root_count) + "/1/1").status, 404);
  EXPECT_EQ(bad.get(at() + "/plain/blocks/0/1").status, 404);  // too few segments
  EXPECT_EQ(bad.get(at() + "/plain/base").status, 404);        // one base for both forms
  EXPECT_EQ(bad.get(at() + "/plain").status, 404);
  EXPECT_EQ(bad.post(at() + "/plain/codec", {}).status, 405);
  EXPECT_EQ(bad.get(at() + "/plain/codec").status, 200);  // still served on the same connection
}

TEST(Http, KeepAliveServesManyRequestsOnOneConnection) {
  Server server;
  HttpTestClient client(server.port());
  for (int i = 0; i < 10; ++i)
    ASSERT_EQ(client.get(i % 2 ? "/models" : splits_url(some_roots(size_t(i + 1)))).status, 200);
  // Pipelined: two requests in one write, two answers in order.
  client.send("GET /models HTTP/1.1\r\nHost: x\r\n\r\nGET " + at() + "/base HTTP/1.1\r\nHost: x\r\n\r\n");
  EXPECT_EQ(client.read().status, 200);
  EXPECT_EQ(client.read().body.size(), served().base_frame->size() - protocol::kFrameHeaderBytes);
  EXPECT_EQ(server.http.stats().connections_opened.load(), 1u);
}

// The connection answers what its buffer holds before reading again, a bounded number in a turn: forty
// requests in one write get forty answers in order, each the one a lone request gets.
TEST(Http, ManyPipelinedRequestsAreAnsweredInOrder) {
  Server server;
  HttpTestClient client(server.port());
  std::vector<std::string> urls;
  std::string requests;
  for (size_t i = 1; i <= 40; ++i) {
    urls.push_back(i % 5 == 0 ? std::string("/models") : splits_url(some_roots(i % 7 + 1)));
    requests += "GET " + urls.back() + " HTTP/1.1\r\nHost: x\r\n\r\n";
  }
  client.send(requests);
  std::vector<HttpReply> replies;
  for (size_t i = 0; i < urls.size(); ++i) replies.push_back(client.read());
  HttpTestClient lone(server.port());
  for (size_t i = 0; i < urls.size(); ++i) {
    const HttpReply alone = lone.get(urls[i]);
    ASSERT_EQ(replies[i].status, 200) << i;
    EXPECT_EQ(replies[i].headers, alone.headers) << i;
    EXPECT_EQ(replies[i].body, alone.body) << i;
  }
  EXPECT_EQ(server.http.stats().requests.load(), 80u);
}

// A request that comes in pieces is answered once whole, within the request deadline; HTTP/1.0 closes
// unless asked to keep the connection, and HTTP/1.1's "Connection: close" is honoured.
TEST(Http, RequestsInPiecesAndConnectionHeaders) {
  Server server;
  HttpTestClient pieces(server.port());
  pieces.send("GET /models/ter");
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  pieces.send("rain/" + served().version + "/base HTTP/1.1\r\nHo");
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  const HttpReply whole = pieces.raw("st: x\r\n\r\n");
  EXPECT_EQ(whole.status, 200);
  EXPECT_EQ(whole.body.size(), served().base_frame->size() - protocol::kFrameHeaderBytes);
  EXPECT_EQ(pieces.get("/models").status, 200);  // kept alive

  HttpTestClient old(server.port());
  const HttpReply closing = old.raw("GET /models HTTP/1.0\r\n\r\n");
  EXPECT_EQ(closing.status, 200);
  EXPECT_TRUE(closing.header("connection").empty());  // HTTP/1.0 closes by default
  EXPECT_TRUE(old.closed_by_server());
  HttpTestClient kept(server.port());
  const HttpReply keeping = kept.raw("GET /models HTTP/1.0\r\nConnection: keep-alive\r\n\r\n");
  EXPECT_EQ(keeping.header("connection"), "keep-alive");
  EXPECT_EQ(kept.raw("GET /models HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n").header("connection"), "close");
  EXPECT_TRUE(kept.closed_by_server());
}

TEST(Http, HostileRequestsGet4xxWhileAGoodClientIsServed) {
  HttpLimits limits;
  limits.max_request_ids = 4;
  Server server(limits);
  HttpTestClient good(server.port());
  ASSERT_EQ(good.get("/models").status, 200);
  HttpTestClient bad(server.port());  // these keep the connection: each request parsed fine
  EXPECT_EQ(bad.post(at() + "/splits", std::vector<uint8_t>(10, 0)).status, 400);  // not a code
  std::vector<uint8_t> code = protocol::encode_split_request(some_roots(3));
  code.pop_back();
  EXPECT_EQ(bad.post(at() + "/splits", code).status, 400);  // truncated
  EXPECT_EQ(bad.get(at() + "/splits/AA+A").status, 400);    // not base64url
  const SplitRequest too_many = some_roots(5);
  ASSERT_EQ(too_many.ids.size(), 5u);
  EXPECT_EQ(bad.post(at() + "/splits", protocol::encode_split_request(too_many)).status, 413);
  const ModelData& model = served().model();
  uint32_t leaf = 0;
  while (!model.is_leaf(leaf)) ++leaf;
  const HttpReply unknown_id = bad.get(splits_url({0, {model.id(leaf)}}));
  EXPECT_EQ(unknown_id.status, 404);
  EXPECT_NE(unknown_id.text().find("no split"), std::string::npos) << unknown_id.text();
  EXPECT_EQ(bad.get(splits_url({0, {{model.root_count, 1}}})).status, 404);  // no such tree
  EXPECT_EQ(bad.get("/models/nothere/base").status, 404);
  EXPECT_EQ(bad.get("/models/terra%69n/base").status, 301);  // the same name: sent to its one URL (HttpFraming)
  for (const char* name : {"terrain%", "terrain%6", "terrain%zz", "a%2Fb", "a%00b", "a\"b"})
    EXPECT_EQ(bad.get(std::string("/models/") + name + "/base").status, 400) << name;
  EXPECT_EQ(bad.get("/elsewhere").status, 404);
  EXPECT_EQ(bad.get("/models?x=1").status, 400);
  const HttpReply wrong_method = bad.post(at() + "/base", {});
  EXPECT_EQ(wrong_method.status, 405);
  EXPECT_EQ(wrong_method.header("allow"), "GET, HEAD");
  EXPECT_EQ(wrong_method.header("cache-control"), "no-store");
  EXPECT_EQ(bad.get(at() + "/splits").status, 405);
  EXPECT_EQ(bad.get(at() + "/base").status, 200);  // still served on the same connection
  // These end their connection: the parser is out of step with the stream.
  EXPECT_EQ(HttpTestClient(server.port()).post(at() + "/splits", std::vector<uint8_t>(20000, 1)).status, 413);
  EXPECT_EQ(HttpTestClient(server.port()).get("/models/" + std::string(5000, 'a')).status, 414);
  EXPECT_EQ(HttpTestClient(server.port()).get("/models/" + std::string(20000, 'a')).status, 414);
  EXPECT_EQ(HttpTestClient(server.port()).get("/models", {{"X-Big", std::string(9000, 'b')}}).status, 431);
  HttpTestClient garbage(server.port());
  EXPECT_EQ(garbage.raw("HELLO\r\n\r\n").status, 400);
  EXPECT_TRUE(garbage.closed_by_server());
  EXPECT_EQ(good.get(splits_url(some_roots(4))).status, 200);
  EXPECT_GE(server.http.stats().client_errors.load(), 16u);
}

TEST(Http, SilentAndSlowPeersAreClosedByTheDeadlines) {
  HttpLimits limits;
  limits.idle_timeout_ms = 300;
  limits.request_timeout_ms = 300;
  Server server(limits);
  const auto start = std::chrono::steady_clock::now();
  HttpTestClient silent(server.port(), 3000);
  EXPECT_TRUE(silent.closed_by_server());
  EXPECT_GE(std::chrono::steady_clock::now() - start, std::chrono::milliseconds(250));
  EXPECT_TRUE(reaches(server.http.stats().connections_timed_out, 1));
  HttpTestClient slow(server.port(), 3000);
  slow.send("GET /models HT");  // begun, never finished
  EXPECT_TRUE(slow.closed_by_server());
  EXPECT_TRUE(reaches(server.http.stats().connections_timed_out, 2));
  HttpTestClient kept(server.port(), 3000);  // keep-alive after an answer: the idle deadline again
  EXPECT_EQ(kept.get("/models").status, 200);
  EXPECT_TRUE(kept.closed_by_server());
  EXPECT_TRUE(reaches(server.http.stats().connections_timed_out, 3));
}

// A peer that sends requests and never reads the answers: once the kernel's buffers are full, nothing is
// taken within the write deadline and the connection is closed, while the idle deadline is far off.
TEST(Http, APeerThatDoesNotReadIsClosedByTheWriteDeadline) {
  HttpLimits limits;
  limits.write_timeout_ms = 300;
  limits.idle_timeout_ms = 60000;
  Server server(limits);
  const std::string url = splits_url(some_roots(64, 8));
  HttpTestClient reader(server.port());
  const size_t answer = reader.get(url).body.size();
  ASSERT_GT(answer, 50000u);
  HttpTestClient deaf(server.port(), 20000);
  std::string requests;
  for (size_t sent = 0; sent < (64u << 20); sent += answer) requests += "GET " + url + " HTTP/1.1\r\nHost: x\r\n\r\n";
  try {
    deaf.send(requests);  // may block until the server gives up on this peer, and then fail
  } catch (const std::exception&) {
  }
  for (int i = 0; i < 400 && server.http.stats().connections_timed_out.load() == 0; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(25));
  EXPECT_EQ(server.http.stats().connections_timed_out.load(), 1u);
  EXPECT_EQ(reader.get("/models").status, 200);  // the others are served meanwhile
}

TEST(Http, ConnectionsOverTheLimitGet503) {
  HttpLimits limits;
  limits.max_connections = 3;
  Server server(limits);
  std::vector<std::unique_ptr<HttpTestClient>> clients;
  for (int i = 0; i < 3; ++i) {
    clients.push_back(std::make_unique<HttpTestClient>(server.port()));
    ASSERT_EQ(clients.back()->get("/models").status, 200);
  }
  HttpTestClient refused(server.port());
  const HttpReply full = refused.read();
  EXPECT_EQ(full.status, 503);
  EXPECT_EQ(server.http.stats().connections_refused.load(), 1u);
  clients.pop_back();
  for (int i = 0; i < 200 && server.http.stats().connections_active.load() >= 3; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  ASSERT_EQ(server.http.stats().connections_active.load(), 2u);
  HttpTestClient later(server.port());
  EXPECT_EQ(later.get("/models").status, 200);
}

}  // namespace
}  // namespace pms::test
