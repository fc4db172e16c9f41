// One session of a load fleet (load_fleet.h): a sender-driven viewer spoken to asynchronously, so one thread
// drives thousands. HELLO, OPEN, BASE, CODEC, a first VIEW from its path's first camera, then it holds its
// front and sends nothing until asked to fly: then it moves along its own path at 30 fps and sends a VIEW
// only when a leaf it holds wants a split for the new view (kim-lee-kobbelt §5.3, as the sender-driven
// client does), one VIEW at a time, timing each from sending it to its final batch.
//
// Instead of a VertexHierarchy (a few MB a session on dragon) it holds its leaves as a bit per model node
// (client::HeldLeaves) and reads what it needs of the hierarchy from the model the server serves, mapped by
// its process: every packet is decoded as a client decodes it, against what a client would hold about v_s
// (the model's values at the wire's grid, only for a held leaf), and must then equal the model's split.
// "A leaf wants a split" is qrefine on the server's own per-node criteria table: exactly when the server's
// answer to a VIEW would not be empty.
#pragma once
#include <utility>  // before asio with C++20 (docs/architecture.md, "Stack")

#include <array>
#include <boost/asio.hpp>
#include <chrono>
#include <cstdint>
#include <deque>
#include <string>
#include <vector>

#include "bench/latency_histogram.h"
#include "bench/soak_client.h"
#include "client/held_leaves.h"
#include "client/server_greeting.h"
#include "protocol/framing.h"
#include "protocol/stream_context.h"
#include "server/catalogue.h"
#include "spm/criteria.h"

namespace pms::bench {

using FleetClock = std::chrono::steady_clock;

// What every session of a process shares: the model as the server serves it.
struct FleetModel {
  const server::ServedModel* served = nullptr;
  std::vector<uint32_t> positions;                   // per node, on the wire's grid
  const std::vector<NodeCriteria>* criteria = nullptr;  // the server's qrefine inputs per node
  float tolerance = 1;
  std::chrono::milliseconds answer_timeout{30000};
  const ModelData& model() const { return served->model(); }
};

// A process's counters, which its sessions add to.
struct FleetCounters {
  LatencyHistogram first_views, views;
  uint64_t views_sent = 0, frames = 0, frames_waiting = 0, splits = 0;
};

class FleetSession;

// What a session tells its fleet.
class FleetListener {
 public:
  virtual void opened(FleetSession& session) = 0;                 // its first VIEW is answered
  virtual void settled(FleetSession& session, bool satisfied) = 0;  // after stop_flying()
  virtual void failed(FleetSession& session) = 0;

 protected:
  ~FleetListener() = default;
};

class FleetSession {
 public:
  FleetSession(boost::asio::io_context& io, const FleetModel& model, SoakPath path, FleetCounters& counters,
               FleetListener& listener);

  void start(const boost::asio::ip::tcp::endpoint& server);
  // 30 frames a second along the path from where it is, starting `offset` from now.
  void fly(FleetClock::duration offset);
  // Stops moving; once its last camera's answer is in and the view wants nothing more (or a few VIEWs
  // did not satisfy it), FleetListener::settled.
  void stop_flying();
  // A session waiting for the server longer than its answer timeout fails.
  void check_deadline(FleetClock::time_point now);
  void close();

  bool failed() const { return failed_; }
  const std::string& error() const { return error_; }
  uint64_t splits() const { return held_.splits(); }

 private:
  enum class Stage : uint8_t { idle, connecting, base, codec, first_view, holding };
  void start_read();
  void on_frame(protocol::Frame frame);
  void on_base(const protocol::Frame& frame);
  void on_batch(const protocol::Frame& frame);
  void check_split(const SplitRecord& split);
  void send(std::vector<uint8_t> frame);
  void write_next();
  void send_view(const Camera& camera);
  void on_tick();
  void settle();
  bool lacks(const Camera& camera) const;
  void fail(const std::string& why);

  boost::asio::ip::tcp::socket socket_;
  boost::asio::steady_timer tick_;
  const FleetModel& model_;
  SoakPath path_;
  FleetCounters& counters_;
  FleetListener& listener_;
  Stage stage_ = Stage::idle;
  std::array<uint8_t, 16384> buffer_;
  protocol::FrameReader reader_;
  client::ServerGreeting greeting_;
  protocol::StreamContext context_;
  client::HeldLeaves held_;
  std::deque<std::vector<uint8_t>> outbox_;
  bool writing_ = false;
  uint64_t frame_ = 0;  // along the path
  Camera camera_;       // the last camera flown to
  FleetClock::time_point next_tick_;
  bool flying_ = false, settling_ = false;
  uint32_t settle_views_ = 0;
  bool pending_ = false;  // a VIEW is unanswered
  uint32_t view_frame_ = 0;
  FleetClock::time_point sent_at_, last_progress_;
  bool failed_ = false, closed_ = false;
  std::string error_;
};

}  // namespace pms::bench
