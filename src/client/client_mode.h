// What a streaming mode is on the client (docs/architecture.md, "Streaming modes"): what OPEN asks for,
// what the client keeps beyond the session every mode shares (BASE, the partial hierarchy, the mesh:
// ClientSession), and what one frame at a camera does. StreamingClient does the rest (connecting,
// HELLO, OPEN, reconnects, counters). A mode lives in its own files and is chosen in one place,
// make_client_mode() (client_modes.cpp).
// Shared with the browser build: single-threaded, no std::ranges algorithms, std::format or coroutines.
#pragma once
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "client/client_session.h"
#include "common/camera.h"
#include "protocol/client_messages.h"
#include "protocol/server_messages.h"
#include "spm/vertex_id.h"

namespace pms::client {

struct FrameReport {
  uint32_t frame = 0;
  uint64_t up_bytes = 0, down_bytes = 0;  // this frame's traffic
  uint64_t vsplits = 0;                   // packets received this frame
  uint64_t faces = 0;
  bool requested = false;  // a VIEW was sent
  double latency_ms = 0;   // VIEW sent -> last split of its answer applied (0 if none)
  // Free-running only (lock-step has none in flight and is always satisfied at a frame's end): requests
  // sent whose final batch has not come, and whether the last one's has and the view lacks nothing.
  uint32_t in_flight = 0;
  bool satisfied = true;
};

// Called with each batch of an answer after the session attached it to the hierarchy.
using BatchHandler = std::function<void(const protocol::VSplits& batch)>;

// What a mode's frame may ask of the server.
class ViewRequests {
 public:
  virtual ~ViewRequests() = default;
  // VIEW for `camera`, then every batch up to its answer's final one (batches of earlier VIEWs too), each
  // attached by the session and then handed to `on_batch`. Returns the splits received; fills the
  // report's requested and latency.
  virtual size_t request_view(const Camera& camera, const BatchHandler& on_batch, FrameReport& report) = 0;
  // DAG_VIEW for `camera` with the session's traversal options, then every DAG_OPS up to its answer's final
  // one, each applied to the session's mesh. Returns the splits received.
  virtual size_t request_dag_view(const Camera& camera, FrameReport& report) = 0;
};

class ClientMode {
 public:
  virtual ~ClientMode() = default;
  // What OPEN asks the server to stream.
  virtual protocol::StreamMode wire_mode() const = 0;
  // Before BASE: how the session must read this mode's packets.
  virtual void prepare(ClientSession& session) const = 0;
  // What OPEN lists to resume a session: by default the leaves of the partial hierarchy held.
  virtual std::vector<VertexId> resume_front(const ClientSession& session) const { return session.known_leaves(); }
  // One frame at `camera`: adapt and request as the mode does, until it has what the view needs.
  virtual void frame(const Camera& camera, ClientSession& session, ViewRequests& server, FrameReport& report) = 0;
  // After the last camera: finish what is still in motion (geomorphs).
  virtual void settle(ClientSession& session) = 0;

  // ---- Free-running (free_running_session.h): the same mode, driven by what arrives; nothing waits ----
  // A VSPLITS batch the session has just attached: a mode that applies splits as they come makes them.
  virtual void on_batch(const protocol::VSplits& batch, ClientSession& session) {
    (void)batch;
    (void)session;
  }
  // Adapts the mesh to `camera` with what is held; whether the view lacks splits the hierarchy does not
  // have. A mode that cannot tell says false and asks at every new camera instead (asks_every_view).
  virtual bool adapt(const Camera& camera, ClientSession& session) {
    (void)camera;
    (void)session;
    return false;
  }
  virtual bool asks_every_view() const { return true; }
  // Whether one answer may stop short of the view by design (the DAG mode's N operations): settling in
  // lock-step then asks again, up to rounds_per_view() times, until an answer changes nothing.
  virtual bool answers_are_capped() const { return false; }
  // Requests at one camera at most, the first included: more only when an answer was cut short (it
  // brought something and the mode still wants more), as the blocking frame re-asks.
  virtual uint32_t rounds_per_view() const { return 1; }
  // The request for `request.view` (its camera, tolerance and frame filled in): VIEW, or DAG_VIEW.
  virtual std::vector<uint8_t> encode_request(const protocol::DagView& request) const {
    return protocol::encode(request.view);
  }
};

std::unique_ptr<ClientMode> make_client_mode(protocol::StreamMode mode);

// OPEN for `model` in `mode`; with the session holding a model already (a lost connection's), the front to
// resume from (kim-lee-kobbelt §5.3), so the server rebuilds its state from it.
protocol::Open open_request(const std::string& model, const ClientMode& mode, const ClientSession& session);

}  // namespace pms::client
