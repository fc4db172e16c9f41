// Sender-driven viewers (client::StreamingClient, lock-step frames) flying their own paths through one
// address, a proxy in front of origins, each reconnecting and resuming (OPEN's resume front) when its
// connection is lost; one event (the test or the bench kills an origin) happens mid-flight. What the
// failover test and the bench's failover figure fly, so both measure the same thing.
#pragma once
#include <chrono>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "client/streaming_client.h"
#include "client/transport.h"
#include "common/camera.h"

namespace pms::bench {

struct FailoverViewerPlan {
  std::vector<Camera> path;
  uint16_t port = 0;           // the proxy's session port, or its HTTP port with websocket_path
  std::string websocket_path;  // non-empty: ws://127.0.0.1:port/PATH (ClientOptions::websocket_path)
};

struct FailoverPlan {
  std::string model;
  float tolerance = 1;
  std::vector<FailoverViewerPlan> viewers;
  // Before frame `event_frame` of its path a viewer meets `event` (empty: none), which happens once every
  // viewer has its session. With `hold_viewers` every viewer waits there until the event is over, so it
  // happens between two frames of every viewer (the bytes of each viewer are then exact); without, the
  // first viewer there runs it and the others fly on, so it may cut answers in the middle.
  size_t event_frame = SIZE_MAX;
  bool hold_viewers = false;
  std::function<void()> event;
  uint32_t reconnect_attempts = 8;
  std::chrono::milliseconds reconnect_delay{50};
};

struct FailoverViewer {
  std::string error;      // empty: the viewer flew its whole path
  uint32_t attempts = 0;  // reconnect attempts (ClientOptions::on_reconnect)
  // Per frame that lost its connection: the loss noticed -> the frame's view satisfied on a new connection
  // (the backoff's delay and the resume included), milliseconds.
  std::vector<double> resume_ms;
  // Of those frames, the ones that had received splits before the loss: an answer the loss cut in the
  // middle, or a later request of the same frame (a frame asks again until its view is satisfied).
  uint32_t lost_mid_frame = 0;
  uint64_t splits_received = 0;  // every VSPLITS packet, over all its sessions
  uint64_t splits_held = 0;      // the split nodes of its hierarchy: one per distinct split received
  client::LinkCounters opened;   // its first session's HELLO, OPEN and their answers (HELLO_OK, BASE, CODEC)
  client::LinkCounters total;    // over every connection
};

// Flies every viewer in a thread of its own; `at_end` (if set) runs on each viewer that finished, on its
// thread, with its client (its mesh at the last camera).
std::vector<FailoverViewer> fly_failover(
    const FailoverPlan& plan, const std::function<void(size_t viewer, client::StreamingClient&)>& at_end = {});

}  // namespace pms::bench
