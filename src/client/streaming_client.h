// A streaming client put together: protocol logic over a transport, frame by frame along a camera path,
// for the headless viewer, the demo, tests and benches; it reconnects and resumes a lost session.
#pragma once
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "client/client_mode.h"
#include "client/client_session.h"
#include "client/dag_management.h"
#include "client/free_running_session.h"
#include "client/server_connection.h"
#include "client/transport.h"
#include "common/camera.h"
#include "protocol/client_messages.h"
#include "protocol/framing.h"
#include "protocol/message_types.h"
#include "protocol/server_messages.h"

namespace pms::client {

struct ClientOptions {
  float tolerance = 1;
  uint32_t morph_frames = 0;
  uint32_t max_ops = 0;  // per frame, 0 = no cap
  uint32_t adapt_budget_us = 0;  // sender: a frame's adaptation time (AdaptOptions::time_budget_us), 0 = no limit
  // The read deadline: a server silent this long while an answer is due (or stuck mid-frame) is lost.
  std::chrono::milliseconds answer_timeout{30000};
  std::chrono::milliseconds connect_timeout{5000};  // each connection, reconnects included
  std::chrono::milliseconds write_timeout{10000};   // a server that stops reading our frames is lost
  std::string name = "pmstream-client";
  // The streaming mode (client_mode.h): sender-driven, or the view-independent baseline.
  protocol::StreamMode mode = protocol::StreamMode::sender_driven;
  // The DAG mode's MANAGE-TRAVERSAL parameters (its view and frame are filled per frame), and how the client
  // sets their mode and N per request (dag_management.h; lock-step only for the frame budget).
  protocol::DagView dag = {};
  DagManagementOptions dag_management = {};
  // A frame that loses a TCP connection reconnects and resumes the session (kim-lee-kobbelt §5.3) up to
  // this many times, waiting reconnect_delay, then twice that, and so on (capped, docs/cli.md); 0 = fail at once.
  uint32_t reconnect_attempts = 0;
  std::chrono::milliseconds reconnect_delay{500};
  // Free-running: the time a frame spends applying what arrived before it returns; the rest waits in the
  // link for the next frame, so that a burst (a long round trip delivers several frames' answers at once)
  // does not make one frame late. At least one frame is applied per displayed frame. Settling applies
  // everything.
  std::chrono::microseconds apply_budget{8000};
  // Sender-driven, free-running: while idle, AHEAD with the camera this many frames on (0: off; lock-step
  // never sends it). FreeRunningSession::set_ahead.
  uint32_t ahead_frames = 0;
  std::function<void(const std::string& reason, uint32_t attempt)> on_reconnect = {};  // told before each try
  // Non-empty: every connection is a WebSocket upgraded at this path of the HTTP server at host:port
  // (ws://HOST:PORT/ws), not a TCP connection to its TCP port.
  std::string websocket_path = {};
};

// The adaptation options `options` give a session's refinement.
inline AdaptOptions adapt_options_of(const ClientOptions& options) {
  AdaptOptions adapt;
  adapt.tolerance = options.tolerance;
  adapt.morph_frames = options.morph_frames;
  adapt.max_ops = options.max_ops;
  adapt.time_budget_us = options.adapt_budget_us;
  return adapt;
}

class StreamingClient : private ViewRequests {
 public:
  // Connects over TCP and says HELLO.
  StreamingClient(const std::string& host, uint16_t port, const ClientOptions& options = {});
  // Connects over TCP and opens `model`: HELLO and OPEN go out together, so BASE comes one round trip
  // after connecting (the server takes OPEN right behind HELLO).
  StreamingClient(const std::string& host, uint16_t port, const ClientOptions& options, const std::string& model);
  // Over any transport (already connected); says HELLO.
  StreamingClient(std::unique_ptr<Transport> transport, const ClientOptions& options = {});
  ~StreamingClient() override;

  protocol::Catalogue list();
  // OPEN; with `resume` (the leaves of a hierarchy held from an earlier session) the server rebuilds its
  // tags from them. Waits for BASE.
  void open(const std::string& model);
  // Reconnects after a lost connection and resumes the session with the hierarchy held (HELLO and OPEN
  // pipelined).
  void resume(const std::string& host, uint16_t port);
  void resume(std::unique_ptr<Transport> transport);

  // One frame of the path, as the mode does it (sender-driven: adapt; when the front needs packets it
  // lacks, VIEW, the whole answer, adapt again). See ClientOptions::reconnect_attempts.
  FrameReport frame(const Camera& camera);
  // Frames at the last camera until nothing changes and nothing moves (geomorphs).
  void settle(const Camera& camera);

  // Free-running (free_running_session.h): applies what has arrived, adapts, sends a request if the view
  // wants one, and returns without waiting for the network. A lost connection is resumed on a later frame
  // once the backoff's delay has passed (ClientOptions::reconnect_attempts), never by sleeping here; the
  // attempt itself connects under connect_timeout, the one wait left (Link connects before it returns).
  FrameReport frame_free_running(const Camera& camera);
  // Free-running frames at `camera`, each followed by waiting for its answers (every wait under
  // answer_timeout), until one asks for nothing more; then the mode's settle (geomorphs).
  void settle_free_running(const Camera& camera);

  ClientSession& session() { return session_; }
  LinkCounters counters() const;  // over every connection this client made
  // Free-running idle time: AHEADs sent, and the splits that came ahead (0 in lock-step).
  uint32_t aheads_sent() const { return free_ ? free_->aheads_sent() : 0; }
  uint64_t ahead_splits() const { return free_ ? free_->ahead_splits() : 0; }
  // The DAG mode: the last DAG_VIEW sent in lock-step (its mode, budget and N as DagManagement set them).
  const protocol::DagView& last_dag_request() const { return last_dag_request_; }

 private:
  FrameReport frame_once(const Camera& camera);
  void reconnect(std::string reason, uint32_t& attempts);
  size_t request_view(const Camera& camera, const BatchHandler& on_batch, FrameReport& report) override;
  size_t request_dag_view(const Camera& camera, FrameReport& report) override;
  void prepare();
  void greet(std::unique_ptr<Transport> transport, Greeting greeting = Greeting::await);
  void close_connection();  // its counters kept
  protocol::Open open_message() const;
  FreeRunningSession& free_running();
  // Free-running: what has arrived, taken without waiting; a lost connection and its next attempt.
  void take_arrived();
  void await_answers();
  void lost(std::string reason);
  void try_resume();

  ClientOptions options_;
  std::unique_ptr<ClientMode> mode_;
  std::unique_ptr<ServerConnection> server_;
  LinkCounters past_;  // counters of closed links
  ClientSession session_;
  std::string model_;
  std::string host_;  // empty: the transport was given, there is nothing to reconnect to
  uint16_t port_ = 0;
  uint32_t frame_ = 0;
  DagManagement dag_management_;
  protocol::DagView last_dag_request_;
  // Free-running.
  std::unique_ptr<FreeRunningSession> free_;
  uint32_t attempts_ = 0;  // reconnects since the last session that got its BASE
  std::string lost_reason_;
  std::chrono::steady_clock::time_point resume_due_;  // while server_ is null
};

}  // namespace pms::client
