// One client's session on a streaming server, as protocol logic without I/O: frames in, frames out.
// It does what every mode shares (HELLO, LIST, OPEN, CLOSE, errors) and hands the rest to the
// SessionMode its OPEN chose (session_mode.h).
#pragma once
#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "protocol/client_messages.h"
#include "protocol/framing.h"
#include "protocol/message_types.h"
#include "server/active_tags.h"
#include "server/catalogue.h"
#include "server/limits.h"
#include "server/session_mode.h"
#include "server/table_builds.h"

namespace pms::server {

// The transport feeds the frames it reads, sends what is queued, and calls pump() while has_work() and
// its send queue has room. An OPEN whose mode's tables are not built yet (model_tables.h) waits for them
// without a thread: the session asks the catalogue's TableBuilds, whose worker calls the transport's wake
// (wake_with) when they are ready or failed; has_work() is then true, and the next pump() sends BASE or the
// ERROR. A session without a wake (in process: tests, the bench) waits for the build on its own thread. No call does
// more than a bounded amount of work whatever the peer sends: receive() only decodes and records (O(frame bytes)); the
// work a message asks for (a VIEW's answer, a resume front) is done by pump(), one slice of at most limits.slice_work
// units at a time, so a transport can share a thread among sessions.
class Session {
 public:
  Session(std::shared_ptr<const Catalogue> catalogue, const ServerLimits& limits);
  ~Session();
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

  // How a transport is told that the tables an OPEN waits for have settled: `wake` runs on a builder's
  // thread and must only post a turn to the session's own thread (table_builds.h). `group` is the
  // transport's, for TableBuilds::forget_group when it stops.
  void wake_with(const void* group, std::function<void()> wake);
  // The mode this session opens times its work into `phases` (ServerLimits::profile_phases).
  void profile_phases(PhaseTimes* phases) { phases_ = phases; }
  // The OPEN waits for its mode's tables.
  bool waiting_for_tables() const { return waiting_.has_value(); }

  // One complete frame from the client (taken, not copied: a resume front keeps its payload).
  // Protocol errors queue an ERROR and mark the session closing.
  void receive(protocol::Frame frame);
  // A transport-level failure (oversized frame, timeout, fault): queue ERROR and close.
  void abort_with(protocol::ErrorCode code, const std::string& text);
  // One slice of the pending work; queues what it completes. False when there was nothing to do.
  bool pump();
  bool has_work() const;
  // Work units (nodes evaluated, split or resumed) the last receive() or pump() call did.
  uint64_t last_work() const { return last_work_; }

  std::deque<Buffer>& outbox() { return outbox_; }
  const std::deque<Buffer>& outbox() const { return outbox_; }
  bool closing() const { return closing_; }
  bool greeted() const { return greeted_; }
  bool opened() const { return mode_ && mode_->opened(); }         // BASE queued
  const SessionMode* session_mode() const { return mode_.get(); }  // nullptr before OPEN
  // Bytes this session holds beyond the shared model (the outbox is the transport's and counted there),
  // and the part of them that grows with the client's front.
  size_t state_bytes() const { return sizeof(*this) + (mode_ ? mode_->state_bytes() : 0); }
  size_t front_bytes() const { return mode_ ? mode_->front_bytes() : 0; }
  // SessionMode::can_park and park: the connection parks a session that stayed silent long enough.
  bool can_park() const { return mode_ && !closing_ && mode_->can_park(); }
  void park() {
    if (can_park()) mode_->park();
  }
  // The client's front, for modes that keep one (empty otherwise): SessionMode::front_tags().
  ActiveTags front_tags() const { return mode_ ? mode_->front_tags() : ActiveTags(); }
  const ServedModel* model() const { return model_; }
  uint64_t splits_sent() const { return mode_ ? mode_->splits_sent() : 0; }
  protocol::StreamMode mode() const { return mode_kind_; }
  // The ERROR code this session ended with, if any (internal = a fault, not the peer's error).
  std::optional<protocol::ErrorCode> error() const { return error_; }
  const std::string& error_text() const { return error_text_; }

 private:
  void handle(protocol::Frame& frame);
  void on_hello(const protocol::Hello& m);
  void on_open(const protocol::OpenHeader& m, protocol::Frame& frame);
  void open_mode(const protocol::OpenHeader& m, protocol::Frame& frame);
  bool tables_settled() const;
  void finish_open();
  void stop_waiting();
  void queue(std::vector<uint8_t> frame);
  void fault(const char* what);

  // The catalogue until OPEN; then the session holds its model alone, so a model a reload dropped goes
  // when its last session ends, not when every session opened before the reload has.
  std::shared_ptr<const Catalogue> catalogue_;
  std::shared_ptr<const std::vector<uint8_t>> list_frame_;  // LIST's answer
  std::shared_ptr<TableBuilds> builds_;
  std::shared_ptr<const ServedModel> model_hold_;
  ServerLimits limits_;
  PhaseTimes* phases_ = nullptr;
  bool greeted_ = false, closing_ = false;
  uint16_t version_ = 0;  // HELLO's: the version this session speaks
  std::optional<protocol::ErrorCode> error_;
  std::string error_text_;
  const ServedModel* model_ = nullptr;
  protocol::StreamMode mode_kind_ = protocol::StreamMode::sender_driven;
  std::unique_ptr<SessionMode> mode_;
  // An OPEN waiting for its tables: the header and the frame (a resume front's payload).
  struct WaitingOpen {
    protocol::OpenHeader header;
    protocol::Frame frame;
  };
  std::optional<WaitingOpen> waiting_;
  TableWaiter waiter_;
  uint64_t last_work_ = 0;
  std::deque<Buffer> outbox_;
};

}  // namespace pms::server
