// The sender-driven streaming server (kim-lee-kobbelt 2005 §5–6; DESIGN.md §4): a catalogue of
// memory-mapped .pms models shared by every session, the per-session protocol logic (which keeps only
// a reference to its model and its windowed active tags), and the TCP transport on Boost.Asio.
#pragma once
#include <atomic>
#include <cstdint>
#include <deque>
#include <memory>
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

struct ServerLimits {
  uint32_t max_sessions = 1000;
  uint32_t max_client_message = 4u << 20;  // a resume front of millions of leaves is ~2 bits each
  uint32_t max_server_message = protocol::kDefaultMaxMessage;
  size_t send_queue_bytes = 64u << 10;     // back-pressure: no new batch while more than this waits
  size_t send_burst_bytes = 1u << 20;      // sent at once by one handler before other sessions get a turn
  uint32_t batch_splits = 1024;            // vsplit packets per VSPLITS message
  uint32_t idle_timeout_ms = 300000;
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
  const std::vector<uint8_t>& catalogue_frame() const { return catalogue_frame_; }
  uint64_t mapped_bytes() const;

 private:
  std::vector<std::unique_ptr<ServedModel>> models_;
  std::vector<uint8_t> catalogue_frame_;
};

using Buffer = std::shared_ptr<const std::vector<uint8_t>>;

// The protocol of one session, without I/O: frames in, frames out. The transport feeds it what it
// reads, sends what it queues, and asks it for more while its send queue has room (pump).
class Session {
 public:
  Session(std::shared_ptr<const Catalogue> catalogue, const ServerLimits& limits);

  // One complete frame from the client. Protocol errors queue an ERROR and mark the session closing.
  void receive(const protocol::Frame& frame);
  // A transport-level failure (oversized frame, timeout): queue ERROR and close.
  void abort_with(protocol::ErrorCode code, const std::string& text);
  // Encodes the next VSPLITS batch of the current VIEW if one is due; false when nothing is left.
  bool pump();

  std::deque<Buffer>& outbox() { return outbox_; }
  bool closing() const { return closing_; }
  // Bytes this session holds beyond the shared model: tags, the VIEW's ranking while it streams,
  // scratch (the outbox is the transport's and counted there).
  size_t state_bytes() const;
  const ActiveTags& tags() const { return tags_; }
  const ServedModel* model() const { return model_; }
  uint64_t splits_sent() const { return splits_sent_; }
  protocol::StreamMode mode() const { return mode_; }

 private:
  void on_hello(const protocol::Hello& m);
  void on_open(const protocol::Open& m);
  void on_view(const protocol::View& m);
  void queue(std::vector<uint8_t> frame);
  // View-independent mode (kim-lee-kobbelt §8, Fig. 9): the plain PM order, prefix by prefix.
  uint64_t prefix_for_view() const;
  bool pump_view_independent();

  std::shared_ptr<const Catalogue> catalogue_;
  ServerLimits limits_;
  bool greeted_ = false, closing_ = false;
  const ServedModel* model_ = nullptr;
  protocol::StreamMode mode_ = protocol::StreamMode::sender_driven;
  protocol::StreamContext context_;  // the model's, without refinement info in view-independent mode
  ActiveTags tags_;
  SelectiveStreamer streamer_;
  ViewCriteria view_;
  uint32_t view_frame_ = 0;
  std::vector<uint32_t> batch_;
  uint64_t splits_sent_ = 0;
  uint64_t sent_ = 0, prefix_end_ = 0;  // view-independent: split_order[0, sent_) sent, [sent_, prefix_end_) due
  bool answering_prefix_ = false;       // view-independent: a VIEW's answer is not final yet
  std::deque<Buffer> outbox_;
};

struct ServerStats {
  std::atomic<uint64_t> sessions_opened{0}, sessions_active{0}, sessions_rejected{0};
  std::atomic<uint64_t> bytes_in{0}, bytes_out{0}, splits_sent{0}, errors_sent{0};
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
