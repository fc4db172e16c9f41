#include "apps/demo_serve.h"

#include <pthread.h>
#include <cctype>
#include <charconv>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "apps/web_root.h"
#include "common/error.h"
#include "server/catalogue.h"
#include "server/http_server.h"
#include "server/limits.h"
#include "server/tcp_server.h"
#include "server/web_options.h"

namespace pms::app {
namespace {

// Shortest text that reads back as the same float, so the link reproduces the camera bit for bit.
std::string number(float value) {
  char text[32];
  const auto [end, error] = std::to_chars(text, text + sizeof text, value);
  return error == std::errc{} ? std::string(text, end) : "0";
}

// RFC 3986 §2.3: unreserved characters as they are, every other byte %XX (a model named after its file
// may hold spaces or '&').
std::string percent_encoded(const std::string& text) {
  static constexpr char kHex[] = "0123456789ABCDEF";
  std::string out;
  for (const unsigned char c : text) {
    if (std::isalnum(c) || c == '-' || c == '.' || c == '_' || c == '~') {
      out += char(c);
    } else {
      out += '%';
      out += kHex[c >> 4];
      out += kHex[c & 15];
    }
  }
  return out;
}

std::string triple(const float (&v)[3]) { return number(v[0]) + "," + number(v[1]) + "," + number(v[2]); }

// The models' routes and the page's files (server/web_options.h) on one port.
std::unique_ptr<server::HttpServer> open_http(std::shared_ptr<const server::Catalogue> catalogue, uint16_t port,
                                              const std::string& web_root) {
  server::WebOptions web;
  web.root = web_root;
  return std::make_unique<server::HttpServer>(std::move(catalogue), server::HttpLimits{}, "127.0.0.1", port, web);
}

// `open(port)`, or where that port is taken and the caller allows it, `open(0)`: any free port.
template <typename Open>
auto on_port(uint16_t port, bool any_if_taken, const Open& open) {
  if (!any_if_taken || port == 0) return open(port);
  try {
    return open(port);
  } catch (const Error& e) {
    std::printf("note:      %s; any free port instead\n", e.what());
    return open(uint16_t(0));
  }
}

}  // namespace

std::string page_link(uint16_t http_port, const std::string& model_name, const Camera& camera, float tolerance) {
  return "http://127.0.0.1:" + std::to_string(http_port) + "/#model=" + percent_encoded(model_name) +
         "&mode=sender&tau=" + number(tolerance) + "&eye=" + triple(camera.eye) + "&target=" + triple(camera.target) +
         "&up=" + triple(camera.up) + "&fovy=" + number(camera.fovy_deg);
}

void serve_demo(const std::string& pms_path, const std::string& model_name, const Camera& first_view,
                const DemoServeOptions& options) {
  // Blocked before the servers' threads start, so they inherit the mask and only sigwait below sees them.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);

  const std::string root = options.web_root.empty() ? default_web_root() : options.web_root;
  const auto catalogue = server::Catalogue::open({pms_path});
  const auto tcp = on_port(options.port, options.any_port_if_taken, [&](uint16_t port) {
    return std::make_unique<server::TcpServer>(catalogue, server::ServerLimits{}, "127.0.0.1", port);
  });
  const auto http = on_port(options.http_port, options.any_port_if_taken,
                            [&](uint16_t port) { return open_http(catalogue, port, root); });
  tcp->start();
  http->start();
  if (!std::filesystem::exists(std::filesystem::path(root) / "index.html"))
    std::printf(
        "warning:   no page in %s: build it with `bash scripts/setup.sh demo` (the web target), or name it "
        "with --web-root\n",
        root.c_str());
  std::printf("server:    %s on 127.0.0.1:%u (TCP) and 127.0.0.1:%u (HTTP: the page, its WebSocket, the HTTP modes)\n",
              model_name.c_str(), unsigned(tcp->port()), unsigned(http->port()));
  std::printf("page:      %s\n", page_link(http->port(), model_name, first_view, options.tolerance).c_str());
  std::printf("           open it in a browser; Ctrl-C stops the server\n");
  std::fflush(stdout);

  int received = 0;
  sigwait(&signals, &received);
  http->stop();
  tcp->stop();
  const server::HttpStats& s = http->stats();
  std::printf("stopped:   %llu HTTP requests, %llu TCP sessions, %llu bytes out\n",
              (unsigned long long)s.requests.load(), (unsigned long long)tcp->stats().sessions_opened.load(),
              (unsigned long long)(s.bytes_out.load() + tcp->stats().bytes_out.load()));
  std::fflush(stdout);
}

}  // namespace pms::app
