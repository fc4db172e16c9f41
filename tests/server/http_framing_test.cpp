// HTTP/1.1 framing as RFC 9112 has it, over real loopback connections and raw bytes: what the server
// refuses on a request's header (Transfer-Encoding, Content-Length, Host, Expect) and that it closes the
// connection then, so no byte after the header is read as a next request; 100 Continue; 414 for a
// request line and 431 for header fields over the limit; one URL per resource.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <vector>

#include "http_test_client.h"
#include "protocol/base64url.h"
#include "protocol/split_request.h"
#include "server/limits.h"
#include "streaming_fixture.h"

namespace pms::test {
namespace {

using server::HttpLimits;

const Fixture& terrain() { return terrain_fixture(20000, 3); }

std::string at() { return model_url(*terrain().catalogue, "terrain"); }  // the model's resources

struct Server : LoopbackHttpServer {
  explicit Server(const HttpLimits& limits = {}) : LoopbackHttpServer(terrain().catalogue, limits) {}
};

// A request code of the first root that has a split.
std::string a_code() {
  const ModelData& model = terrain().catalogue->find("terrain")->model();
  uint32_t root = 0;
  while (model.is_leaf(root)) ++root;
  const std::vector<uint8_t> code = protocol::encode_split_request({0, {model.id(root)}});
  return {code.begin(), code.end()};
}

// What follows every refused request below: a request of its own, which the server must never answer.
const std::string kSmuggled = "GET /models HTTP/1.1\r\nHost: x\r\n\r\n";

// Sends `request` then kSmuggled in one write: the status of the one answer, which must say the connection
// closes, and then the close with nothing more.
int refused_and_closed(uint16_t port, const std::string& request) {
  HttpTestClient client(port);
  const HttpReply reply = client.raw(request + kSmuggled);
  const bool http10 = request.find(" HTTP/1.0\r\n") != std::string::npos;  // closes without saying so
  EXPECT_EQ(reply.header("connection"), http10 ? "" : "close") << request;
  EXPECT_EQ(client.rest_until_closed(), "") << request;  // the smuggled GET got no answer
  return reply.status;
}

std::string post_header(const std::string& fields) {
  return "POST " + at() + "/splits HTTP/1.1\r\nHost: x\r\n" + fields + "\r\n";
}

std::string chunked(const std::string& body) {
  char size[16];
  std::snprintf(size, sizeof size, "%zx", body.size());
  return size + ("\r\n" + body + "\r\n0\r\n\r\n");
}

TEST(HttpFraming, ATransferEncodingOtherThanChunkedAloneIsRefusedAndTheConnectionClosed) {
  Server server;
  const struct {
    const char* coding;
    int status;
  } cases[] = {{"chunked, identity", 501}, {"identity", 501},         {"gzip", 501},     {"gzip, chunked", 501},
               {"chunked;x=1", 501},       {"chunked, chunked", 400}, {"chunk ed", 400}, {"", 400}};
  for (const auto& [coding, status] : cases) {
    const std::string fields = std::string("Transfer-Encoding: ") + coding + "\r\n";
    EXPECT_EQ(refused_and_closed(server.port(), "GET /models HTTP/1.1\r\nHost: x\r\n" + fields + "\r\n"), status)
        << coding;
    EXPECT_EQ(refused_and_closed(server.port(), post_header(fields)), status) << coding;
  }
  // HTTP/1.0 has no transfer codings (RFC 9112 §6.1).
  EXPECT_EQ(
      refused_and_closed(server.port(), "POST " + at() + "/splits HTTP/1.0\r\nTransfer-Encoding: chunked\r\n\r\n" +
                                            chunked(a_code())),
      400);
}

TEST(HttpFraming, TransferEncodingWithContentLengthIsRefusedAndTheConnectionClosed) {
  Server server;
  const std::string code = a_code();
  const std::string length = "Content-Length: " + std::to_string(code.size()) + "\r\n";
  for (const std::string& fields :
       {"Transfer-Encoding: identity\r\n" + length, length + "Transfer-Encoding: chunked\r\n",
        "Transfer-Encoding: chunked\r\n" + length})
    EXPECT_EQ(refused_and_closed(server.port(), post_header(fields) + code), 400) << fields;
}

TEST(HttpFraming, TwoDifferentContentLengthsAreRefusedAndTheConnectionClosed) {
  Server server;
  const std::string code = a_code();
  const std::string n = std::to_string(code.size()), more = std::to_string(code.size() + 40);
  EXPECT_EQ(refused_and_closed(server.port(),
                               post_header("Content-Length: " + n + "\r\nContent-Length: " + more + "\r\n") + code),
            400);
  EXPECT_EQ(refused_and_closed(server.port(), post_header("Content-Length: " + n + ", " + more + "\r\n") + code), 400);
  HttpTestClient same(server.port());  // the same value twice is one length (RFC 9110 §8.6)
  EXPECT_EQ(same.raw(post_header("Content-Length: " + n + ", " + n + "\r\n") + code).status, 200);
}

// The one transfer coding the server takes still frames the body: the answer is the GET form's.
TEST(HttpFraming, AChunkedBodyIsReadAsTheRequestsBody) {
  Server server;
  HttpTestClient client(server.port());
  const std::string code = a_code();
  const HttpReply chunked_post = client.raw(post_header("Transfer-Encoding: chunked\r\n") + chunked(code));
  ASSERT_EQ(chunked_post.status, 200) << chunked_post.text();
  const HttpReply get = client.get(at() + "/splits/" +
                                   protocol::base64url_encode(std::vector<uint8_t>(code.begin(), code.end())));
  EXPECT_EQ(chunked_post.body, get.body);
  EXPECT_EQ(client.raw(kSmuggled).status, 200);  // kept alive, in step
}

TEST(HttpFraming, AnHttp11RequestNeedsOneHostAndAnyRequestAtMostOne) {
  Server server;
  EXPECT_EQ(refused_and_closed(server.port(), "GET /models HTTP/1.1\r\n\r\n"), 400);
  EXPECT_EQ(refused_and_closed(server.port(), "GET /models HTTP/1.1\r\nHost: a\r\nHost: b\r\n\r\n"), 400);
  EXPECT_EQ(refused_and_closed(server.port(), "GET /models HTTP/1.1\r\nHost: a\r\nHost: a\r\n\r\n"), 400);
  EXPECT_EQ(refused_and_closed(server.port(), "GET /models HTTP/1.0\r\nHost: a\r\nHost: b\r\n\r\n"), 400);
  EXPECT_EQ(refused_and_closed(server.port(), "GET /models HTTP/1.1\r\nHost: a/b\r\n\r\n"), 400);
  HttpTestClient client(server.port());
  for (const char* host : {"example.com", "127.0.0.1:8080", "[::1]:80", ""})
    EXPECT_EQ(client.raw(std::string("GET /models HTTP/1.1\r\nHost: ") + host + "\r\n\r\n").status, 200) << host;
  HttpTestClient old(server.port());
  EXPECT_EQ(old.raw("GET /models HTTP/1.0\r\n\r\n").status, 200);  // HTTP/1.0 need not send it
}

// The client sends its header, waits for the 100 (the read's own deadline: a server that never sends it
// fails the read), and only then the body.
TEST(HttpFraming, AClientThatWaitsForContinueGetsItThenItsAnswer) {
  Server server;
  HttpTestClient client(server.port());
  const std::string code = a_code();
  client.send(post_header("Expect: 100-continue\r\nContent-Length: " + std::to_string(code.size()) + "\r\n"));
  EXPECT_EQ(client.read().status, 100);
  client.send(code);
  const HttpReply answer = client.read();
  EXPECT_EQ(answer.status, 200) << answer.text();
  client.send(post_header("Expect: 100-Continue\r\nTransfer-Encoding: chunked\r\n"));
  EXPECT_EQ(client.read().status, 100);
  client.send(chunked(code));
  EXPECT_EQ(client.read().body, answer.body);
  // No body, nothing to wait for: the answer alone.
  EXPECT_EQ(client.raw("GET /models HTTP/1.1\r\nHost: x\r\nExpect: 100-continue\r\n\r\n").status, 200);
}

TEST(HttpFraming, AnExpectationOtherThanContinueGets417AndTheConnectionClosed) {
  Server server;
  const std::string code = a_code();
  const std::string length = "Content-Length: " + std::to_string(code.size()) + "\r\n";
  EXPECT_EQ(refused_and_closed(server.port(), post_header("Expect: 100-continue, other\r\n" + length) + code), 417);
  EXPECT_EQ(refused_and_closed(server.port(), "GET /models HTTP/1.1\r\nHost: x\r\nExpect: 200-ok\r\n\r\n"), 417);
}

// Beast takes the request line once it ends within the header limit, and then the fields within the same
// limit again: a line of the limit's length (its CRLF included) is a request, one byte more a 414; fields
// of the limit's length (the empty line included) are a request, one byte more a 431, whether or not
// the bytes that end them have come.
TEST(HttpFraming, ARequestLineOverTheLimitGets414AndHeaderFieldsOverIt431) {
  HttpLimits limits;
  limits.max_header_bytes = 1024;
  Server server(limits);
  const auto line_of = [](size_t bytes) {  // GET /models/aaa...a HTTP/1.1 CRLF: an unknown model, 404
    return "GET /models/" + std::string(bytes - std::string("GET /models/ HTTP/1.1\r\n").size(), 'a') + " HTTP/1.1\r\n";
  };
  const auto fields_of = [](size_t bytes) {  // Host: x CRLF X: bbb...b CRLF CRLF
    return "Host: x\r\nX: " + std::string(bytes - std::string("Host: x\r\nX: \r\n\r\n").size(), 'b') + "\r\n\r\n";
  };
  HttpTestClient at_limits(server.port());
  EXPECT_EQ(at_limits.raw(line_of(1024) + "Host: x\r\n\r\n").status, 404);
  EXPECT_EQ(at_limits.raw("GET /models HTTP/1.1\r\n" + fields_of(1024)).status, 200);
  EXPECT_EQ(refused_and_closed(server.port(), line_of(1025) + "Host: x\r\n\r\n"), 414);
  EXPECT_EQ(refused_and_closed(server.port(), line_of(1025) + fields_of(100)), 414);
  EXPECT_EQ(refused_and_closed(server.port(), "GET /models HTTP/1.1\r\n" + fields_of(1025)), 431);
  // Neither ended yet: a line still going at the limit, a field still going at the limit.
  HttpTestClient line_going(server.port());
  line_going.send("GET /models/" + std::string(2000, 'a'));
  EXPECT_EQ(line_going.read().status, 414);
  EXPECT_TRUE(line_going.closed_by_server());
  HttpTestClient field_going(server.port());
  field_going.send("GET /models HTTP/1.1\r\nHost: x\r\nX: " + std::string(2000, 'b'));
  EXPECT_EQ(field_going.read().status, 431);
  EXPECT_TRUE(field_going.closed_by_server());
}

// A spelling of a URL other than its canonical one (escapes of unreserved characters, lower-case hex, a
// model name's raw sub-delims) is sent to the canonical URL, on every route; the canonical URL is served.
TEST(HttpFraming, AUrlSpelledAnotherWayIsRedirectedToTheCanonicalOne) {
  Server server;
  HttpTestClient client(server.port());
  const std::string raw_code = a_code();
  const std::string code = protocol::base64url_encode(std::vector<uint8_t>(raw_code.begin(), raw_code.end()));
  const std::string v = at().substr(at().rfind('/') + 1);
  const struct {
    std::string url, canonical;
  } cases[] = {{"/models/%74errain/" + v + "/base", at() + "/base"},
               {"/models/terra%69n/" + v + "/base", at() + "/base"},
               {"/%6Dodels", "/models"},
               {at() + "/b%61se", at() + "/base"},
               {at() + "/splits/%41" + code, at() + "/splits/A" + code},
               {at() + "/blocks/%30/1/2", at() + "/blocks/0/1/2"},
               {at() + "/%6Dultilevel", at() + "/multilevel"},
               {at() + "/compressed/levels/%30", at() + "/compressed/levels/0"},
               {"/models/a%2cb/base", "/models/a%2Cb/base"},
               {"/models/a,b/base", "/models/a%2Cb/base"},
               {"/models/%7e%C3%bc/base", "/models/~%C3%BC/base"}};
  for (const auto& [url, canonical] : cases) {
    const HttpReply moved = client.get(url);
    EXPECT_EQ(moved.status, 301) << url;
    EXPECT_EQ(moved.header("location"), canonical) << url;
    EXPECT_EQ(moved.header("cache-control"), "no-store") << url;
    EXPECT_EQ(client.head(url).header("location"), canonical) << url;
  }
  for (const std::string& canonical : std::vector<std::string>{"/models", at() + "/base"})
    EXPECT_EQ(client.get(canonical).status, 200);
  EXPECT_EQ(client.get("/models/a%2Cb/base").status, 404);  // the redirect's target: no such model, no loop
  const HttpReply post =
      client.post("/models/%74errain/" + v + "/splits", std::vector<uint8_t>(raw_code.begin(), raw_code.end()));
  EXPECT_EQ(post.status, 308);  // a POST is sent on as a POST
  EXPECT_EQ(post.header("location"), at() + "/splits");
  EXPECT_EQ(client.get("/models/terrain%/base").status, 400);  // no path: nothing to redirect to
}

}  // namespace
}  // namespace pms::test
