// The Viewer of the session modes (sender, sender-plain, vi, dag) for a host that moves the bytes itself:
// the browser's WebSocket (one binary message = one TCP protocol frame, unchanged), a test's socket. It owns
// the protocol logic (ClientSession, the ClientMode, FreeRunningSession, all I/O-free) and two queues: the
// frames to send (take_outgoing) and the bytes received (on_bytes), which frame() applies. Nothing waits:
// opening is asynchronous (frames report `opening` until BASE, and CODEC, are in), and a lost connection
// (disconnected) keeps the mesh; the next connected() resumes the session with HELLO and an OPEN that lists
// the front held (kim-lee-kobbelt §5.3), as StreamingClient::resume does. The host paces reconnects.
// Shared with the browser build: no I/O, single-threaded.
#pragma once
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "client/client_mode.h"
#include "client/client_session.h"
#include "client/free_running_session.h"
#include "client/server_greeting.h"
#include "client/viewer.h"
#include "protocol/framing.h"

namespace pms::client {

class MessageSessionViewer : public Viewer {
 public:
  // options.mode picks the mode; its tolerance, morph_frames, max_ops, dag, name and apply_budget apply.
  MessageSessionViewer(const ClientOptions& options, const std::string& model);
  ~MessageSessionViewer() override;

  // A new connection is open: HELLO and OPEN are queued (a held model's OPEN resumes it).
  void connected();
  // Bytes from the server in any chunking; frame() applies them. pms::Error once more than the frame
  // limit allows is announced (the stream cannot be read on).
  void on_bytes(std::span<const uint8_t> bytes);
  // The connection is gone: the frames that came whole are applied (the front a resume lists must hold
  // them), a cut one is dropped, and what is in flight will not be answered.
  void disconnected();
  bool is_connected() const { return connected_; }
  // The frames to send now, in order, each whole (header included).
  std::vector<std::vector<uint8_t>> take_outgoing();

  // Applies what has arrived (within options.apply_budget; the rest waits for the next frame), adapts,
  // queues a request when the view wants one. pms::Error for an ERROR from the server or a frame the
  // session refuses: final.
  ViewerReport frame_view(const Camera& camera) override;
  // Tolerance, the sender's geomorphs, the DAG's traversal, budget and max-ops: the next frame asks anew
  // with them, at the same camera too.
  void retune(const ViewerTuning& tuning) override;
  // This viewer cannot wait: pms::Error. Frame until settled() instead.
  void settle(const Camera& camera) override;
  // The last view satisfied, nothing in flight, queued or in motion (geomorphs).
  bool settled() const;
  Mesh mesh() const override;
  ViewParams view_params(const Camera& camera) const override { return session_.view_params(camera); }
  const char* received_unit() const override { return "vsplits"; }
  uint64_t received_total() const override { return session_.splits_received(); }
  uint64_t up_bytes() const override { return counters_.bytes_up; }
  uint64_t down_bytes() const override { return counters_.bytes_down; }
  nlohmann::json totals() const override;

  ClientSession& session() { return session_; }

 protected:
  const SelectiveRefinement* refinement() const override {
    return session_.has_model() ? &session_.refinement() : nullptr;
  }

 private:
  void apply(protocol::Frame&& frame);
  void take_arrived();
  void queue(std::vector<uint8_t> frame);

  ClientOptions options_;
  std::string model_;
  std::unique_ptr<ClientMode> mode_;
  ClientSession session_;
  std::unique_ptr<FreeRunningSession> free_;
  ServerGreeting greeting_;
  protocol::FrameReader reader_;
  std::vector<std::vector<uint8_t>> outgoing_;
  LinkCounters counters_;
  bool connected_ = false;
};

}  // namespace pms::client
