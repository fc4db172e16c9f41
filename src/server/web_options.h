// What the HTTP server needs beyond its HTTP limits to serve the browser: the page's files and the
// WebSocket's sessions (docs/operating.md, "The page" and "WebSocket").
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "server/limits.h"
#include "server/static_site.h"

namespace pms::server {

struct WebOptions {
  std::string root;  // --web-root; empty or missing: the page's routes answer 404 saying how to build it
  SiteLimits site;
  // --ws-allowed-origin: the Origins a WebSocket upgrade may come from; empty = the same origin only
  // ("http://" + the request's Host). An upgrade without an Origin (not a browser) is taken.
  std::vector<std::string> allowed_origins;
  // The WebSocket sessions' bounds, the TCP sessions' own (--max-sessions and the rest): one client
  // costs the server the same over either. The sessions cap is the WebSocket's own count of max_sessions.
  ServerLimits sessions;
};

}  // namespace pms::server
