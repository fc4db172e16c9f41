#include "client/session_viewer.h"

#include "client/websocket_link.h"
#include "common/error.h"
#include "protocol/url_segment.h"

namespace pms::client {

void split_host_port(const std::string& text, std::string& host, uint16_t& port, const std::string& where) {
  const size_t colon = text.rfind(':');
  if (colon == std::string::npos || colon == 0) fail(where, "'" + text + "' is not HOST:PORT");
  host = text.substr(0, colon);
  const std::optional<uint16_t> parsed = protocol::parse_port(std::string_view(text).substr(colon + 1));
  if (!parsed) fail(where, "'" + text + "' has no valid port");
  port = *parsed;
}

namespace {

// HELLO and OPEN together: the first picture (BASE) one round trip after connecting.
// HOST:PORT is the TCP port; ws://HOST:PORT/ws the HTTP port's WebSocket, for a client that only HTTP reaches.
std::unique_ptr<StreamingClient> connect(const std::string& server, ClientOptions options, const std::string& model) {
  if (server.starts_with("ws://")) {
    const std::optional<WebSocketUrl> url = parse_websocket_url(server);
    if (!url) fail("--server", "'" + server + "' is not ws://HOST:PORT[/PATH]");
    options.websocket_path = url->path;
    return std::make_unique<StreamingClient>(url->host, url->port, options, model);
  }
  std::string host;
  uint16_t port = 0;
  split_host_port(server, host, port, "--server");
  return std::make_unique<StreamingClient>(host, port, options, model);
}

}  // namespace

SessionViewer::SessionViewer(const std::string& server, const ClientOptions& options, Pacing pacing,
                             const std::string& model)
    : client_(connect(server, options, model)), pacing_(pacing), dag_(options.mode == protocol::StreamMode::dag) {}

ViewerReport SessionViewer::frame_view(const Camera& camera) {
  const bool lock_step = pacing_ == Pacing::lock_step;
  const FrameReport r = lock_step ? client_->frame(camera) : client_->frame_free_running(camera);
  ViewerReport report;
  report.frame = r.frame;
  report.faces = r.faces;
  report.vertices = client_->session().mesh().vertex_count();
  report.received = r.vsplits;
  report.up_bytes = r.up_bytes;
  report.down_bytes = r.down_bytes;
  report.in_flight = r.in_flight;
  report.latency_ms = r.latency_ms;
  report.satisfied = r.satisfied;  // lock-step: always, the VIEW's whole answer is applied
  if (dag_ && lock_step) {
    const protocol::DagView& asked = client_->last_dag_request();
    report.details = {{"dag_management", asked.management == DagMode::free ? "free" : "budget"},
                      {"dag_max_ops", asked.max_ops}};
  }
  return report;
}

void SessionViewer::settle(const Camera& camera) {
  if (pacing_ == Pacing::lock_step) return client_->settle(camera);
  client_->settle_free_running(camera);
}

Mesh SessionViewer::mesh() const { return current_mesh(client_->session().refinement()); }

ViewParams SessionViewer::view_params(const Camera& camera) const { return client_->session().view_params(camera); }

uint64_t SessionViewer::received_total() const { return client_->session().splits_received(); }

nlohmann::json SessionViewer::totals() const {
  const LinkCounters c = client_->counters();
  return {{"total_up_payload_bytes", c.payload_up()},
          {"total_down_payload_bytes", c.payload_down()},
          {"aheads_sent", client_->aheads_sent()},
          {"ahead_vsplits", client_->ahead_splits()}};
}

}  // namespace pms::client
