// The sender-driven mode (kim-lee-kobbelt 2005 §5.3, §6.1): the server keeps the client's front and
// answers each VIEW with SelectiveStreaming over it, in batches of vsplit packets with refinement info, so
// the client can refine on its own until its front needs more. The front is windowed active tags while a
// VIEW is answered, and coded (compact_front.h) in between, unless ServerLimits::compact_fronts is off. A
// session can be resumed: OPEN then carries the leaves the client holds, and the front is rebuilt from them.
// Its plain option (StreamMode::sender_plain, kim-lee-kobbelt §6.3) streams the same splits in the same
// order, but as plain_packets.h codes them: the client's actual cut vertices, no refinement info.
// Idle time (kim-lee-kobbelt §9): AHEAD names the view the client expects to reach; while no VIEW is being
// answered and the outbox is empty, SelectiveStreaming for that view goes out in small batches flagged
// ahead, within ServerLimits::ahead_budget_bytes. A VIEW stops it at once and is answered first; the
// ahead answer then restarts over the front the VIEW left. The client holds what comes ahead and makes it
// only when a view wants it, so its meshes are those of a session without AHEAD.
#pragma once
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "protocol/client_messages.h"
#include "protocol/framing.h"
#include "protocol/stream_context.h"
#include "server/active_tags.h"
#include "server/compact_front.h"
#include "server/selective_streaming.h"
#include "server/session_mode.h"

namespace pms::server {

class SenderDrivenMode : public SessionMode {
 public:
  // Queues BASE at once for a fresh session; a resumed one decodes its front first (pump()).
  SenderDrivenMode(const protocol::OpenHeader& open, protocol::Frame& open_frame, const ModeContext& context);
  ~SenderDrivenMode() override;

  void receive(const protocol::ClientMessage& message) override;
  bool has_work() const override { return resume_ || view_.pending || ahead_due(); }
  void pump(uint64_t& work) override;
  bool opened() const override { return !resume_; }
  void stop() override;
  size_t state_bytes() const override;
  size_t front_bytes() const override { return tags_.memory_bytes() + parked_.memory_bytes(); }
  uint64_t splits_sent() const override { return splits_sent_; }
  ActiveTags front_tags() const override;
  bool can_park() const override;
  uint64_t ahead_bytes() const { return ahead_bytes_; }
  void park() override { park_front(); }

 private:
  static constexpr size_t kAheadBatchSplits = 64;  // a VIEW that comes waits behind at most this many (and a chain)
  struct Resume;  // an OPEN's resume front, checked and applied a slice at a time
  void queue_base();
  void pump_resume(uint64_t& work);
  void pump_answer(uint64_t& work);
  bool ahead_due() const;
  void pump_ahead(uint64_t& work);
  void stop_ahead();
  void emit_batch(size_t count, bool final);
  // The front between answers: coded (compact_fronts), and decoded when an answer starts.
  void park_front();
  void unpark();
  void park_if_due();  // at once when park_after_ms is 0; else the connection parks it (can_park)

  ModeContext context_;
  std::unique_ptr<Resume> resume_;
  ActiveTags tags_;       // the front while a VIEW is answered (always, without compact_fronts)
  CompactFront parked_;  // the front between answers (compact_fronts)
  LatestView view_;
  Importance importance_;
  SelectiveStreamer streamer_;
  std::vector<uint32_t> batch_;  // splits chosen and not yet sent
  // The plain option: the context without refinement info, and batch_'s cut vertices on the client's mesh.
  bool plain_ = false;
  protocol::StreamContext plain_wire_;
  std::vector<ActualCuts> batch_cuts_;
  uint64_t splits_sent_ = 0;
  // Idle time: the latest AHEAD, its answer (never while view_ is pending) and the bytes it has cost.
  LatestView ahead_;
  Importance ahead_importance_;
  SelectiveStreamer ahead_streamer_;
  std::vector<uint32_t> ahead_batch_;
  uint64_t ahead_bytes_ = 0;
};

}  // namespace pms::server
