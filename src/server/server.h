// The sender-driven streaming server (kim-lee-kobbelt 2005 §5–6; DESIGN.md §4): a catalogue of
// memory-mapped .pms models shared by every session, the per-session protocol logic (which keeps only
// a reference to its model and its windowed active tags), and the TCP transport on Boost.Asio.
#pragma once
#include <atomic>
#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "pm/pm.h"
#include "protocol/protocol.h"
#include "refine/criteria.h"
#include "server/active_tags.h"
#include "server/selective_streaming.h"

namespace pms::server {

// One model as every session sees it: the mapped file, the BASE frame encoded once, and qrefine's
// inputs per node decoded once (positions snapped to the wire grid, so the server evaluates exactly
// the numbers its clients hold).
struct ServedModel {
  std::string name;  // file name without .pms
  std::string path;
  std::unique_ptr<PmsFile> file;
  protocol::ModelInfo info;
  protocol::StreamContext context;
  std::shared_ptr<const std::vector<uint8_t>> base_frame;
  std::vector<NodeCriteria> criteria;  // per node
  std::vector<uint32_t> split_rank;    // per node: its index in split_order (view-independent mode); leaves kNone
  DependencyFilter dependencies;
  protocol::PacketTable packets;  // sender-driven packets (with refinement info)
  const ModelView& view() const { return file->view(); }
};

// Every bound the server puts on a peer (docs/operating.md says what each one protects against).
struct ServerLimits {
  uint32_t max_sessions = 1000;
  uint32_t max_client_message = 4u << 20;  // a resume front of millions of leaves is ~2 bits each
  uint32_t max_server_message = protocol::kDefaultMaxMessage;  // BASE, CATALOGUE and VSPLITS; checked at start
  size_t send_queue_bytes = 64u << 10;     // back-pressure: no new batch while more than this waits
  size_t send_burst_bytes = 1u << 20;      // sent at once by one handler before other sessions get a turn
  uint32_t batch_splits = 1024;            // vsplit packets per VSPLITS message
  uint32_t slice_work = 2048;              // nodes evaluated or split per Session::pump() call (~0.15 ms)
  uint32_t turn_us = 1000;                 // one session's turn on an I/O thread before others get theirs
  uint32_t max_message_rate = 500;         // messages a session may send per second (bursts of as many); 0 = any
  uint32_t idle_timeout_ms = 120000;       // no message in and no answer byte out for this long: closed
  uint32_t handshake_timeout_ms = 10000;   // HELLO and OPEN must be done within this of connecting
  uint32_t frame_timeout_ms = 10000;       // a frame, once begun, must arrive whole within this
  uint32_t write_timeout_ms = 10000;       // answer bytes waiting and none taken for this long: closed
  uint32_t accept_backoff_ms = 1000;       // longest pause after a failed accept (EMFILE...), doubling from 10 ms
  uint32_t position_bits = protocol::kDefaultPositionBits;
  uint32_t threads = 0;                    // I/O threads; 0 = one per core
};

class Catalogue {
 public:
  // Every FILE.pms given and every *.pms in the directories given; throws pms::Error naming the file
  // for an unreadable or corrupt model, or two models with the same name.
  static std::shared_ptr<const Catalogue> open(const std::vector<std::string>& paths,
                                               uint32_t position_bits = protocol::kDefaultPositionBits);
  const ServedModel* find(const std::string& name) const;
  const std::vector<std::unique_ptr<ServedModel>>& models() const { return models_; }
  // The CATALOGUE frame, encoded once and shared by every LIST's answer.
  const std::shared_ptr<const std::vector<uint8_t>>& catalogue_frame() const { return catalogue_frame_; }
  uint64_t mapped_bytes() const;
  // pms::Error naming the model when a frame the server would send can exceed limits.max_server_message
  // (a BASE, the CATALOGUE, a full VSPLITS batch), or the batch is too large to slice.
  void check_limits(const ServerLimits& limits) const;

 private:
  std::vector<std::unique_ptr<ServedModel>> models_;
  std::shared_ptr<const std::vector<uint8_t>> catalogue_frame_;
};

using Buffer = std::shared_ptr<const std::vector<uint8_t>>;

// The protocol of one session, without I/O: frames in, frames out. The transport feeds it the frames it
// reads, sends what it queues, and calls pump() while has_work() and its send queue has room. No call
// does more than a bounded amount of work whatever the peer sends: receive() only decodes and records
// (O(frame bytes)); the work a message asks for (a VIEW's answer, a resume front) is done by pump(), one
// slice of at most limits.slice_work nodes at a time, so a transport can share a thread among sessions.
class Session {
 public:
  Session(std::shared_ptr<const Catalogue> catalogue, const ServerLimits& limits);
  ~Session();
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

  // One complete frame from the client (taken, not copied: a resume front keeps its payload).
  // Protocol errors queue an ERROR and mark the session closing.
  // A VIEW replaces the one being answered (what was not sent yet is judged again under the new one), so
  // any number of VIEWs in a row cost one answer.
  void receive(protocol::Frame frame);
  // A transport-level failure (oversized frame, timeout, fault): queue ERROR and close.
  void abort_with(protocol::ErrorCode code, const std::string& text);
  // One slice of the pending work; queues a VSPLITS (or BASE, after a resume) when one is complete.
  // False when there was nothing to do.
  bool pump();
  bool has_work() const;
  // Work units (nodes evaluated, split or resumed) the last receive() or pump() call did.
  uint64_t last_work() const { return last_work_; }

  std::deque<Buffer>& outbox() { return outbox_; }
  const std::deque<Buffer>& outbox() const { return outbox_; }
  bool closing() const { return closing_; }
  bool greeted() const { return greeted_; }
  bool opened() const { return model_ != nullptr && !resume_; }  // BASE queued
  // Bytes this session holds beyond the shared model: tags, the VIEW's ranking while it streams, a
  // pending resume front, scratch (the outbox is the transport's and counted there).
  size_t state_bytes() const;
  const ActiveTags& tags() const { return tags_; }
  const ServedModel* model() const { return model_; }
  uint64_t splits_sent() const { return splits_sent_; }
  protocol::StreamMode mode() const { return mode_; }
  // The ERROR code this session ended with, if any (internal = a fault, not the peer's error).
  std::optional<protocol::ErrorCode> error() const { return error_; }
  const std::string& error_text() const { return error_text_; }

 private:
  struct Resume;      // an OPEN's resume front, checked and applied a slice at a time
  struct ViewPrefix;  // view-independent: the prefix of the PM order a VIEW needs, found a slice at a time
  void handle(protocol::Frame& frame);
  void on_hello(const protocol::Hello& m);
  void on_open(const protocol::OpenHeader& m, protocol::Frame& frame);
  void on_view(const protocol::View& m);
  void finish_open();
  void queue(std::vector<uint8_t> frame);
  void fault(const char* what);
  bool pump_resume(uint64_t& work);
  bool pump_sender(uint64_t& work);
  bool pump_view_independent(uint64_t& work);
  void emit_batch(size_t count, bool final);
  const Importance& importance();

  std::shared_ptr<const Catalogue> catalogue_;
  ServerLimits limits_;
  bool greeted_ = false, closing_ = false;
  std::optional<protocol::ErrorCode> error_;
  std::string error_text_;
  const ServedModel* model_ = nullptr;
  protocol::StreamMode mode_ = protocol::StreamMode::sender_driven;
  protocol::StreamContext context_;  // the model's, without refinement info in view-independent mode
  std::unique_ptr<Resume> resume_;
  ActiveTags tags_;
  SelectiveStreamer streamer_;
  std::unique_ptr<ViewPrefix> prefix_;
  ViewCriteria view_;
  std::optional<uint32_t> view_frame_;  // the VIEW being answered
  bool view_pending_ = false;           // a VIEW arrived and its answer is not final yet
  bool restart_ = false;                // pump() starts answering the latest VIEW afresh
  Importance importance_;               // refinement_priority under view_
  std::vector<uint32_t> batch_;
  uint64_t splits_sent_ = 0;
  uint64_t sent_ = 0;  // view-independent: split_order[0, sent_) sent
  uint64_t last_work_ = 0;
  std::deque<Buffer> outbox_;
};

struct ServerStats {
  std::atomic<uint64_t> sessions_opened{0}, sessions_active{0}, sessions_refused{0};
  std::atomic<uint64_t> sessions_timed_out{0};  // closed by a deadline (handshake, idle, frame, write)
  std::atomic<uint64_t> sessions_failed{0};     // ended by an internal fault (ERROR internal)
  std::atomic<uint64_t> protocol_errors{0};     // ERRORs for a peer's bad message or sequence
  std::atomic<uint64_t> bytes_in{0}, bytes_out{0}, splits_sent{0}, errors_sent{0};
  std::atomic<uint64_t> accept_failures{0};
  std::atomic<uint64_t> longest_turn_us{0};    // the longest one session held an I/O thread in one go
  std::atomic<uint64_t> peak_state_bytes{0};   // the largest Session::state_bytes() seen
  std::atomic<uint64_t> peak_buffer_bytes{0};  // the same without the active tags
};

// TCP transport: `threads` I/O threads, one strand per connection, every read bounded by the frame
// limit and every wait by the idle timeout.
class TcpServer {
 public:
  TcpServer(std::shared_ptr<const Catalogue> catalogue, const ServerLimits& limits, const std::string& host,
            uint16_t port);
  ~TcpServer();
  TcpServer(const TcpServer&) = delete;
  TcpServer& operator=(const TcpServer&) = delete;

  uint16_t port() const;  // the bound port (useful with port 0)
  void start();           // runs the I/O threads in the background
  void stop();            // closes every session and joins the threads
  void wait();            // blocks until stop() (from a signal handler or another thread)
  const ServerStats& stats() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace pms::server
