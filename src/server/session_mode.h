// What a streaming mode is on the server (docs/architecture.md, "Streaming modes"): the state it keeps per
// session beyond the shared model, and the work the messages of its own ask for. The Session does what
// every mode shares (HELLO, LIST, OPEN, CLOSE, errors, the outbox); everything after OPEN is the mode's.
// A mode lives in its own files and is chosen in one place, open_session_mode() (session_modes.cpp).
#pragma once
#include <cstddef>
#include <cstdint>
#include <deque>
#include <memory>
#include <vector>

#include "protocol/client_messages.h"
#include "protocol/dispatch.h"
#include "protocol/framing.h"
#include "server/active_tags.h"
#include "server/catalogue.h"
#include "server/limits.h"
#include "server/phase_times.h"
#include "server/selective_streaming.h"
#include "spm/criteria.h"

namespace pms::server {

using Buffer = std::shared_ptr<const std::vector<uint8_t>>;

// What a mode works with: its session's model and limits, and the outbox its frames go to.
struct ModeContext {
  const ServedModel& served;
  const ServerLimits& limits;
  std::deque<Buffer>& outbox;
  PhaseTimes* phases = nullptr;  // the server's, when it profiles phases
  void queue(std::vector<uint8_t> frame) const {
    outbox.push_back(std::make_shared<const std::vector<uint8_t>>(std::move(frame)));
  }
};

// Every call is bounded whatever the peer sends: receive() decodes and records (O(message bytes)); the
// work a message asks for is done by pump(), at most limits.slice_work units a call. Errors are thrown:
// ProtocolError for the peer's, anything else is the server's fault (the Session turns either into ERROR).
class SessionMode {
 public:
  SessionMode() = default;
  // A mode's importance function points into the mode itself (its LatestView): it stays where it was made.
  SessionMode(const SessionMode&) = delete;
  SessionMode& operator=(const SessionMode&) = delete;
  virtual ~SessionMode() = default;

  // A message after OPEN other than CLOSE (VIEW, for today's modes).
  virtual void receive(const protocol::ClientMessage& message) = 0;
  virtual bool has_work() const = 0;
  // One slice of the pending work; adds the units it did to `work`.
  virtual void pump(uint64_t& work) = 0;
  // BASE is queued (a resume may first decode its front over several pumps).
  virtual bool opened() const = 0;
  // Frees what pending work holds: the session is ending.
  virtual void stop() = 0;

  // Bytes held beyond the shared model, and the part of them that grows with the client's front.
  virtual size_t state_bytes() const = 0;
  virtual size_t front_bytes() const = 0;
  virtual uint64_t splits_sent() const = 0;
  // The mode holds state it could keep in a form that costs less between answers, at the cost of a pass to
  // restore it (the sender-driven front, ServerLimits::park_after_ms), and park() moves it there.
  virtual bool can_park() const { return false; }
  virtual void park() {}
  // The client's front as active tags (decoded when the mode holds it coded), for the modes that keep one:
  // tests and the bench audit it. Empty for the others.
  virtual ActiveTags front_tags() const { return {}; }
};

// The mode an OPEN asks for, over the model it names. `open_frame` is the OPEN itself: a mode that takes
// a resume front keeps its payload. Throws ProtocolError for an OPEN the mode cannot take.
std::unique_ptr<SessionMode> open_session_mode(const protocol::OpenHeader& open, protocol::Frame& open_frame,
                                               const ModeContext& context);

// The VIEW being answered, for the modes driven by VIEW: a newer one replaces an unanswered one, and the
// answer restarts once, at the next pump, however many came in between.
struct LatestView {
  ViewCriteria criteria;  // derived as the client derives them: bit-identical qrefine on both ends
  uint32_t frame = 0;     // echoed in the answer's VSPLITS
  bool pending = false;   // received and not yet answered in full
  bool restart = false;   // the answer is to start afresh

  void record(const protocol::View& view, const ModelData& model);
  // refinement_priority of a node under the recorded view (reads `criteria` when called, so it follows
  // every later record()).
  Importance importance(const std::vector<NodeCriteria>& per_node) const;
};

}  // namespace pms::server
