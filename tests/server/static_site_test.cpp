// The page's files on the HTTP port (serve --web-root): MIME types, ETag and 304, HEAD, Cache-Control,
// every spelling of a way out of the root refused, no listing, the size cap, a missing root, and the API's
// routes first.
#include <gtest/gtest.h>
#include <filesystem>
#include <fstream>

#include "http_test_client.h"
#include "server/http_server.h"
#include "server/site_path.h"
#include "streaming_fixture.h"
#include "test_support.h"

namespace pms::test {
namespace {

namespace fs = std::filesystem;

void write(const fs::path& path, const std::string& text) {
  fs::create_directories(path.parent_path());
  std::ofstream(path, std::ios::binary) << text;
}

// A page tree, with a secret beside it that no URL may reach.
struct Site {
  Site() {
    const fs::path dir = temp_dir() / "site";
    root = dir / "web";
    write(root / "index.html", "<!doctype html><title>pmstream</title>");
    write(root / "js" / "page.js", "export const x = 1;");
    write(root / "js" / "page.mjs", "export const y = 2;");
    write(root / "css" / "page.css", "body{}");
    write(root / "pmstream_core.wasm", std::string("\0asm\1\0\0\0", 8));
    write(root / "a.json", "{}");
    write(root / "a.js.map", "{}");
    write(root / "i.png", "png");
    write(root / "i.svg", "<svg/>");
    write(root / "favicon.ico", "ico");
    write(root / ".hidden", "hidden");
    write(dir / "secret.txt", "secret");
    fs::create_symlink(dir / "secret.txt", root / "out.txt");
    fs::create_symlink(root / "js" / "page.js", root / "in.js");
  }
  fs::path root;
};

struct Server : LoopbackHttpServer {
  explicit Server(const std::string& root, const server::SiteLimits& site = {})
      : LoopbackHttpServer(terrain_fixture(2000, 1).catalogue, {}, options(root, site)) {}
  static server::WebOptions options(const std::string& root, const server::SiteLimits& site) {
    server::WebOptions web;
    web.root = root;
    web.site = site;
    return web;
  }
};

TEST(StaticSite, ServesEachTypeWithItsMime) {
  const Site site;
  Server server(site.root.string());
  HttpTestClient client(server.port());
  const std::pair<const char*, const char*> cases[] = {
      {"/", "text/html; charset=utf-8"},
      {"/index.html", "text/html; charset=utf-8"},
      {"/js/page.js", "text/javascript; charset=utf-8"},
      {"/js/page.mjs", "text/javascript; charset=utf-8"},
      {"/css/page.css", "text/css; charset=utf-8"},
      {"/pmstream_core.wasm", "application/wasm"},
      {"/a.json", "application/json"},
      {"/a.js.map", "application/json"},
      {"/i.png", "image/png"},
      {"/i.svg", "image/svg+xml"},
      {"/favicon.ico", "image/x-icon"},
      {"/in.js", "text/javascript; charset=utf-8"},  // a symlink inside the root
  };
  for (const auto& [target, type] : cases) {
    const HttpReply reply = client.get(target);
    EXPECT_EQ(reply.status, 200) << target;
    EXPECT_EQ(reply.header("content-type"), type) << target;
    EXPECT_EQ(reply.header("cache-control"), "no-cache") << target;
    EXPECT_FALSE(reply.header("etag").empty()) << target;
  }
  EXPECT_EQ(client.get("/pmstream_core.wasm").body.size(), 8u);
  EXPECT_EQ(client.get("/?model=terrain&mode=sender").text(), "<!doctype html><title>pmstream</title>");
}

TEST(StaticSite, EtagRevalidatesAndChangesWithTheFile) {
  const Site site;
  Server server(site.root.string());
  HttpTestClient client(server.port());
  const HttpReply first = client.get("/js/page.js");
  const std::string etag = first.header("etag");
  ASSERT_EQ(etag.front(), '"');  // strong
  const HttpReply again = client.get("/js/page.js", {{"If-None-Match", etag}});
  EXPECT_EQ(again.status, 304);
  EXPECT_TRUE(again.body.empty());
  write(site.root / "js" / "page.js", "export const x = 22;");
  const HttpReply changed = client.get("/js/page.js", {{"If-None-Match", etag}});
  EXPECT_EQ(changed.status, 200);
  EXPECT_EQ(changed.text(), "export const x = 22;");
  EXPECT_NE(changed.header("etag"), etag);
}

TEST(StaticSite, HeadHasTheHeadersWithoutTheBody) {
  const Site site;
  Server server(site.root.string());
  HttpTestClient client(server.port());
  const HttpReply get = client.get("/index.html");
  const HttpReply head = client.head("/index.html");
  EXPECT_EQ(head.status, 200);
  EXPECT_TRUE(head.body.empty());
  EXPECT_EQ(head.header("content-length"), std::to_string(get.body.size()));
  EXPECT_EQ(head.header("etag"), get.header("etag"));
  EXPECT_EQ(client.post("/index.html", {}).status, 405);
}

TEST(StaticSite, NoWayOutOfTheRootAndNoListing) {
  const Site site;
  Server server(site.root.string());
  for (const char* target : {"/../secret.txt", "/%2e%2e/secret.txt", "/.%2E/secret.txt", "/js/..%2fsecret.txt",
                             "/js%2f..%2f..%2fsecret.txt", "/..%5csecret.txt", "/out.txt", "/.hidden", "/js/",
                             "/js", "/css/", "//etc/passwd", "/index.html%00", "/%zz", "/missing.js",
                             "/js/%2e/page.js", "/js/./page.js"}) {
    HttpTestClient client(server.port());
    const HttpReply reply = client.raw(std::string("GET ") + target + " HTTP/1.1\r\nHost: x\r\n\r\n");
    EXPECT_GE(reply.status, 400) << target;
    EXPECT_EQ(reply.text().find("secret"), std::string::npos) << target;
    EXPECT_EQ(reply.text().find("export"), std::string::npos) << target;
  }
}

TEST(StaticSite, PathsThatNameAFileOrNothing) {
  EXPECT_EQ(server::site_path("/"), "index.html");
  EXPECT_EQ(server::site_path("/js/page.js?x=1"), "js/page.js");
  EXPECT_EQ(server::site_path("/a%20b.js"), "a b.js");
  for (const char* bad : {"", "x", "/..", "/%2E%2e", "/a/../b", "/a//b", "/a/", "/a%2fb", "/a%5cb", "/a\\b",
                          "/a%00", "/%"})
    EXPECT_FALSE(server::site_path(bad).has_value()) << bad;
}

TEST(StaticSite, FilesOverTheCapAreRefused) {
  const Site site;
  write(site.root / "big.js", std::string(5000, 'x'));
  Server server(site.root.string(), server::SiteLimits{4096, 1u << 20});
  HttpTestClient client(server.port());
  EXPECT_EQ(client.get("/big.js").status, 403);
  EXPECT_EQ(client.get("/index.html").status, 200);
}

TEST(StaticSite, AMissingRootSaysHowToBuildThePage) {
  Server server((temp_dir() / "no-such-web").string());
  HttpTestClient client(server.port());
  const HttpReply reply = client.get("/");
  EXPECT_EQ(reply.status, 404);
  EXPECT_NE(reply.text().find("the page is not built"), std::string::npos);
  EXPECT_EQ(client.get("/models").status, 200);  // the API still answers
}

TEST(StaticSite, TheApiKeepsItsRoutes) {
  const Site site;
  write(site.root / "models" / "index.html", "not the catalogue");
  Server server(site.root.string());
  HttpTestClient client(server.port());
  const HttpReply models = client.get("/models");
  EXPECT_EQ(models.status, 200);
  EXPECT_EQ(models.header("content-type"), "application/json");
  EXPECT_EQ(client.get("/models/index.html").status, 404);
  EXPECT_EQ(client.get("/" + std::string(5000, 'a') + ".js").status, 414);  // the URL bound holds here too
}

}  // namespace
}  // namespace pms::test
