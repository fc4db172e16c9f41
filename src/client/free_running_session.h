// The session modes (sender, sender-plain, vi, dag) free-running, as events and without I/O: the server's
// frames go in as they arrive (on_frame), a displayed frame at a camera gives the request to send, if any
// (frame). Nothing here waits: the native edge (StreamingClient) feeds it what its Link already holds, the
// browser build what its WebSocket delivered.
//
// A request goes out when the camera moved since the last one sent and the mode wants one (sender: qrefine
// misses packets; the others cannot tell, so at every new camera). The server lets a newer VIEW overtake
// one it has not answered yet, and only the newest gets a final batch; every batch is applied all the same,
// since the server's state assumes it. At a camera that stays, a request is repeated only once its answer
// is in and was cut short (it brought something, and the mode still wants more), at most
// ClientMode::rounds_per_view() times: the blocking frame's re-asks, spread over frames.
// Idle time (kim-lee-kobbelt §9, set_ahead; sender-driven only): a frame that sends no VIEW, with none in
// flight and a view that lacks nothing, whose camera moved since the frame before, sends AHEAD with the
// camera extrapolated that many frames on (common/camera.h). The client, not the server, predicts: it sees
// every frame's camera, the server only the VIEWs, which come exactly when the client is not idle. What
// comes ahead is attached as held data like any batch; adapt() makes it only when a view wants it.
// Shared with the browser build: single-threaded, no std::ranges algorithms, std::format or coroutines.
#pragma once
#include <chrono>
#include <cstdint>
#include <deque>
#include <optional>
#include <vector>

#include "client/client_mode.h"
#include "client/client_session.h"
#include "client/dag_management.h"
#include "common/camera.h"
#include "protocol/client_messages.h"
#include "protocol/framing.h"

namespace pms::client {

class FreeRunningSession {
 public:
  using Clock = std::chrono::steady_clock;

  // `request` is what every request carries besides its camera and number: the tolerance (view.tolerance)
  // and the DAG mode's traversal; `management` sets the DAG mode's FREE or BUDGET per request, counting the
  // requests in flight (its frame budget is lock-step's: N stays the request's here). The session holds
  // the model already (BASE is in).
  FreeRunningSession(ClientSession& session, ClientMode& mode, const protocol::DagView& request,
                     const DagManagementOptions& management = {});

  // A frame from the server: VSPLITS attached and handed to the mode, DAG_OPS applied, a resumed session's
  // BASE and CODEC taken. A final batch answers its request and every earlier one still open. pms::Error
  // for anything else, or what the session refuses.
  void on_frame(const protocol::Frame& frame, Clock::time_point now);
  // One displayed frame: adapts to `camera` (the modes that refine on their own) and returns the request
  // to send now, empty if none. Fills the report but for its bytes.
  std::vector<uint8_t> frame(const Camera& camera, Clock::time_point now, FrameReport& report);
  // The connection is gone: what is in flight will never be answered, and no request goes out until a
  // new connection's BASE (and CODEC) have come in.
  void restart();
  // What every request carries from now on; the next frame asks with it, at the same camera too.
  void set_request(const protocol::DagView& request);
  // Idle time: AHEAD with the camera `frames` frames on (0: never).
  void set_ahead(uint32_t frames) { ahead_frames_ = frames; }
  uint64_t ahead_splits() const { return ahead_splits_; }  // received in batches sent ahead
  uint32_t aheads_sent() const { return aheads_; }
  bool opening() const { return opening_; }
  uint32_t in_flight() const { return uint32_t(sent_.size()); }
  // The last request's final batch is in and the view lacks nothing the mode can tell.
  bool satisfied() const { return !opening_ && sent_.empty() && !lacks_; }

 private:
  struct Sent {
    uint32_t number;
    Clock::time_point at;
  };

  bool wants_request(const Camera& camera) const;
  std::vector<uint8_t> request(const Camera& camera, Clock::time_point now);
  std::vector<uint8_t> ahead(const Camera& camera);  void on_base(const protocol::Frame& frame);
  void received(uint64_t splits, uint64_t operations, uint32_t number, bool final, Clock::time_point now);

  ClientSession& session_;
  ClientMode& mode_;
  DagManagement management_;  // holds the request
  std::deque<Sent> sent_;           // requests whose final batch has not come, oldest first
  uint32_t requests_ = 0;           // the last request's number
  uint32_t frames_ = 0;             // displayed frames
  std::optional<Camera> asked_;     // the camera of the last request
  uint32_t rounds_ = 0;             // requests at asked_
  uint64_t answer_operations_ = 0;  // splits and collapses received since the last request
  bool lacks_ = false;              // the last adapt: the view misses packets
  bool opening_ = false, codec_due_ = false;
  // Idle time.
  uint32_t ahead_frames_ = 0;
  std::optional<Camera> previous_;  // the camera of the frame before
  uint32_t aheads_ = 0;
  uint64_t ahead_splits_ = 0;
  // Since the last displayed frame.
  uint64_t splits_ = 0;
  double latency_ms_ = 0;
};

}  // namespace pms::client
