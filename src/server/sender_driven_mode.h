// The sender-driven mode (kim-lee-kobbelt 2005 §5.3, §6.1): the server keeps the client's front as
// windowed active tags and answers each VIEW with SelectiveStreaming over it, in batches of vsplit packets
// with refinement info, so the client can refine on its own until its front needs more. A session can be
// resumed: OPEN then carries the leaves the client holds, and the tags are rebuilt from them.
// Its plain option (StreamMode::sender_plain, kim-lee-kobbelt §6.3) streams the same splits in the same
// order, but as plain_packets.h codes them: the client's actual cut vertices, no refinement info.
#pragma once
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "protocol/client_messages.h"
#include "protocol/framing.h"
#include "protocol/stream_context.h"
#include "server/active_tags.h"
#include "server/selective_streaming.h"
#include "server/session_mode.h"

namespace pms::server {

class SenderDrivenMode : public SessionMode {
 public:
  // Queues BASE at once for a fresh session; a resumed one decodes its front first (pump()).
  SenderDrivenMode(const protocol::OpenHeader& open, protocol::Frame& open_frame, const ModeContext& context);
  ~SenderDrivenMode() override;

  void receive(const protocol::ClientMessage& message) override;
  bool has_work() const override { return resume_ || view_.pending; }
  void pump(uint64_t& work) override;
  bool opened() const override { return !resume_; }
  void stop() override;
  size_t state_bytes() const override;
  size_t front_bytes() const override { return tags_.memory_bytes(); }
  uint64_t splits_sent() const override { return splits_sent_; }
  const ActiveTags* tags() const override { return &tags_; }

 private:
  struct Resume;  // an OPEN's resume front, checked and applied a slice at a time
  void queue_base();
  void pump_resume(uint64_t& work);
  void pump_answer(uint64_t& work);
  void emit_batch(size_t count, bool final);

  ModeContext context_;
  std::unique_ptr<Resume> resume_;
  ActiveTags tags_;
  LatestView view_;
  Importance importance_;
  SelectiveStreamer streamer_;
  std::vector<uint32_t> batch_;  // splits chosen and not yet sent
  // The plain option: the context without refinement info, and batch_'s cut vertices on the client's mesh.
  bool plain_ = false;
  protocol::StreamContext plain_wire_;
  std::vector<ActualCuts> batch_cuts_;
  uint64_t splits_sent_ = 0;
};

}  // namespace pms::server
