// The interactive half of `pmstream demo`: the model served on loopback (TCP for native clients, HTTP for the
// page and its WebSocket), the page's link printed with the model and a first camera in it, served until
// SIGINT or SIGTERM.
#pragma once
#include <cstdint>
#include <string>

#include "common/camera.h"

namespace pms::app {

struct DemoServeOptions {
  uint16_t port = 7300;            // TCP (0: any free port)
  uint16_t http_port = 7301;       // the page, its WebSocket and the HTTP modes (0: any free port)
  bool any_port_if_taken = false;  // a port another program holds: take any free one instead of failing
  std::string web_root;            // the assembled site; empty: default_web_root()
  float tolerance = 1;             // the page's τ, carried in the link
};

// The page's link (docs/web.md, "The link"): model, sender mode, τ and `camera` in the hash.
std::string page_link(uint16_t http_port, const std::string& model_name, const Camera& camera, float tolerance);

// Serves `pms_path` (as `model_name`) until SIGINT or SIGTERM, then prints the totals and returns.
void serve_demo(const std::string& pms_path, const std::string& model_name, const Camera& first_view,
                const DemoServeOptions& options);

}  // namespace pms::app
