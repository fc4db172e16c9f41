// The sender-driven streaming client (kim-lee-kobbelt 2005 §5.3): it keeps the partial vertex hierarchy
// and the selectively refined mesh, runs SelectiveRefinement every frame, and sends VIEW only when the
// front needs vsplit packets it does not have. ClientSession is the protocol logic without I/O (shared
// with the browser build); Link is the TCP transport (its own I/O thread, bounded queues, deadlines);
// StreamingClient puts the two together for the headless viewer, the demo, tests and benches.
#pragma once
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "common/error.h"
#include "protocol/protocol.h"
#include "refine/adapt.h"
#include "refine/camera.h"
#include "refine/refine.h"

namespace pms::client {

// ---- protocol logic ------------------------------------------------------------------------------------

class ClientSession {
 public:
  // Builds the base mesh, hierarchy and refinement loop from a BASE. With `keep` (a resumed session whose
  // hierarchy is already here) the BASE only has to match the model held.
  void on_base(const protocol::Base& base);
  // Attaches a batch's packets as leaves of the partial hierarchy (UpdateVHierarchy); in view-independent
  // mode also applies each split to the mesh at once (they come in PM order, so each one can be made).
  void on_vsplits(const protocol::VSplits& batch);

  bool has_model() const { return refinement_ != nullptr; }
  const protocol::StreamContext& context() const { return context_; }
  const protocol::Base& base() const { return base_; }
  VertexHierarchy& hierarchy() { return *hierarchy_; }
  SelectiveMesh& mesh() { return *mesh_; }
  SelectiveRefinement& refinement() { return *refinement_; }
  ViewParams view_params(const Camera& camera) const;
  // The leaves of the partial hierarchy: what a resumed session sends in OPEN.
  std::vector<VertexId> known_leaves() const;
  uint64_t splits_received() const { return splits_received_; }

  AdaptOptions adapt_options;
  // Set before on_base: a view-independent session's packets carry no refinement info.
  protocol::StreamMode mode = protocol::StreamMode::sender_driven;

 private:
  protocol::Base base_;
  protocol::StreamContext context_;
  std::unique_ptr<VertexHierarchy> hierarchy_;
  std::unique_ptr<SelectiveMesh> mesh_;
  std::unique_ptr<SelectiveRefinement> refinement_;
  uint64_t splits_received_ = 0;
};

// ---- transport -----------------------------------------------------------------------------------------

struct LinkCounters {
  uint64_t bytes_up = 0, bytes_down = 0;      // whole frames, as on the wire
  uint64_t frames_up = 0, frames_down = 0;
  uint64_t payload_up() const { return bytes_up - frames_up * protocol::kFrameHeaderBytes; }
  uint64_t payload_down() const { return bytes_down - frames_down * protocol::kFrameHeaderBytes; }
};

// The connection could not be made or is gone (refused, closed, reset, or past a connect, write or answer
// deadline): the session can be resumed on a new one. Any other pms::Error (an ERROR from the server, a
// malformed message) is final.
struct ConnectionError : Error {
  using Error::Error;
};

// How a client reaches a server: frames out, frames in. TCP here (Link); the browser's WebSocket and
// the bench's in-process pipe are others.
class Transport {
 public:
  virtual ~Transport() = default;
  // Hands the frame over for sending (it may still be on its way when this returns); throws
  // ConnectionError once the connection is gone.
  virtual void send(const std::vector<uint8_t>& frame) = 0;
  // The next frame from the server; std::nullopt after `timeout`. Throws ConnectionError once the
  // connection is gone (with the reason) and nothing is left to read.
  virtual std::optional<protocol::Frame> receive(std::chrono::milliseconds timeout) = 0;
  virtual LinkCounters counters() const = 0;
};

// A Link's limits. Every wait on the server has one: a peer that stops answering, reading or sending
// mid-frame is a ConnectionError after its deadline, never a hang.
struct LinkOptions {
  std::chrono::milliseconds connect_timeout{5000};  // resolve + TCP handshake
  std::chrono::milliseconds write_timeout{10000};   // a queued frame's bytes make no progress this long
  std::chrono::milliseconds read_timeout{30000};    // a frame that has begun arriving is not complete
  size_t max_queued_bytes = 64u << 20;              // received payloads waiting for receive()
  uint32_t max_message = protocol::kDefaultMaxMessage;
  // Frames waiting to be written; one more frame over it means the server stopped reading. A frame
  // into an empty queue always fits, so this bounds the backlog, not a single (OPEN) frame.
  size_t max_send_queue_bytes = 16u << 20;
};

// A TCP connection owned by its own I/O thread: connect, reads and writes all run there (asio's
// chat_client shape). Received frames wait in a bounded queue (the socket is not read while it is full,
// so a slow consumer back-pressures the server instead of growing memory); sent frames wait in a bounded
// queue and go out one after another. A failed connect, a lost connection or a missed deadline surfaces
// as ConnectionError; close() and the destructor stop and join the thread without waiting on the server.
class Link : public Transport {
 public:
  Link(const std::string& host, uint16_t port, const LinkOptions& options = {});
  Link(const std::string& host, uint16_t port, size_t max_queued_bytes,
       uint32_t max_message = protocol::kDefaultMaxMessage);
  ~Link() override;
  Link(const Link&) = delete;
  Link& operator=(const Link&) = delete;

  void send(const std::vector<uint8_t>& frame) override;
  std::optional<protocol::Frame> receive(std::chrono::milliseconds timeout) override;
  LinkCounters counters() const override;
  void close();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// ---- the two together ----------------------------------------------------------------------------------

struct FrameReport {
  uint32_t frame = 0;
  uint64_t up_bytes = 0, down_bytes = 0;  // this frame's traffic
  uint64_t vsplits = 0;                   // packets received this frame
  uint64_t faces = 0;
  bool requested = false;                 // a VIEW was sent
  double latency_ms = 0;                  // VIEW sent -> last split of its answer applied (0 if none)
};

struct ClientOptions {
  float tolerance = 1;
  uint32_t morph_frames = 0;
  uint32_t max_ops = 0;  // per frame, 0 = no cap
  // The read deadline: a server silent this long while an answer is due (or stuck mid-frame) is lost.
  std::chrono::milliseconds answer_timeout{30000};
  std::chrono::milliseconds connect_timeout{5000};  // each connection, reconnects included
  std::chrono::milliseconds write_timeout{10000};   // a server that stops reading our frames is lost
  std::string name = "pmstream-client";
  // view_independent: the baseline of kim-lee-kobbelt §8 Fig. 9. Splits arrive in PM order without
  // refinement info and are applied as they come; qrefine never runs here, so the client sends VIEW every
  // frame (it cannot know what it lacks) and the server decides how much of the PM order the view needs.
  protocol::StreamMode mode = protocol::StreamMode::sender_driven;
  // A frame that loses a TCP connection reconnects and resumes the session (kim-lee-kobbelt §5.3) up to
  // this many times, waiting reconnect_delay, then twice that, and so on (capped at 8 s); 0 = fail at once.
  uint32_t reconnect_attempts = 0;
  std::chrono::milliseconds reconnect_delay{500};
  std::function<void(const std::string& reason, uint32_t attempt)> on_reconnect = {};  // told before each try
};

class StreamingClient {
 public:
  // Connects over TCP and says HELLO.
  StreamingClient(const std::string& host, uint16_t port, const ClientOptions& options = {});
  // Over any transport (already connected); says HELLO.
  StreamingClient(std::unique_ptr<Transport> transport, const ClientOptions& options = {});
  ~StreamingClient();

  protocol::Catalogue list();
  // OPEN; with `resume` (the leaves of a hierarchy held from an earlier session) the server rebuilds its
  // tags from them. Waits for BASE.
  void open(const std::string& model);
  // Reconnects after a lost connection and resumes the session with the hierarchy held.
  void resume(const std::string& host, uint16_t port);
  void resume(std::unique_ptr<Transport> transport);

  // One frame of the path: adapt to the camera; when the front needs packets it lacks, send VIEW, wait
  // for the whole answer and adapt again, until the view is satisfied. View-independent: VIEW, and apply
  // the answer's splits in order.
  FrameReport frame(const Camera& camera);  // see ClientOptions::reconnect_attempts
  // Frames at the last camera until nothing changes and nothing moves (geomorphs).
  void settle(const Camera& camera);

  ClientSession& session() { return session_; }
  LinkCounters counters() const;  // over every connection this client made

 private:
  protocol::Frame expect(protocol::MessageType type);
  FrameReport frame_once(const Camera& camera);
  void reconnect(std::string reason, uint32_t& attempts);
  size_t request(const Camera& camera, FrameReport& report);
  void adapt_and_request(const Camera& camera, FrameReport& report);  // sender-driven frame
  void greet(std::unique_ptr<Transport> transport);

  ClientOptions options_;
  std::unique_ptr<Transport> link_;
  LinkCounters past_;  // counters of closed links
  ClientSession session_;
  std::string model_;
  std::string host_;  // empty: the transport was given, there is nothing to reconnect to
  uint16_t port_ = 0;
  uint32_t frame_ = 0;
};

}  // namespace pms::client
