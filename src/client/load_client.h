// A protocol-only load client, as wrk is for HTTP: it speaks the sender-driven protocol through the same
// ServerConnection as every client (HELLO, OPEN, a VIEW per frame, every VSPLITS batch read and decoded)
// but refines nothing, so a bench's cores go to the server it measures and latency is the server's, not
// the client's adaptation. The bench's E11 and soak drive `serve` with it.
#pragma once
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "client/held_leaves.h"
#include "client/server_connection.h"
#include "common/camera.h"
#include "protocol/framing.h"
#include "protocol/message_types.h"
#include "protocol/stream_context.h"
#include "spm/hierarchy.h"
#include "spm/split_record.h"
#include "spm/vertex_hierarchy.h"
#include "spm/vertex_id.h"

namespace pms::client {

struct LoadClientOptions {
  std::chrono::milliseconds answer_timeout{120000};
  // When set (the model the server serves), the client keeps the leaves of the partial hierarchy its
  // splits describe, a bit per node of the model, so it can resume (OPEN with those leaves, kim-lee-kobbelt
  // §5.3); and every split received must be of one of them, so none arrives twice, across a resume too.
  const ModelData* model = nullptr;
};

class LoadClient {
 public:
  LoadClient(std::string host, uint16_t port, std::string model_name, LoadClientOptions options = {});
  ~LoadClient();

  // A new connection: HELLO, OPEN, BASE. `resume` (with LoadClientOptions::model) sends the leaves held,
  // else the session starts from the base mesh and the leaves are the roots again.
  void open(bool resume);
  // VIEW, then every batch up to its final one; the milliseconds from sending it to that batch.
  // Throws pms::Error for an ERROR, a split of no held leaf or a late answer; ConnectionError when the
  // connection is gone.
  double view(const Camera& camera, float tolerance);
  // Drops the connection without a word, as a lost network does.
  void drop();

  bool connected() const { return server_ != nullptr; }
  bool holds_splits() const { return held_ && held_->splits() > 0; }
  uint64_t splits_received() const { return splits_received_; }

 private:
  void start_hierarchy(const protocol::Base& base);

  std::string host_, model_name_;
  uint16_t port_;
  LoadClientOptions options_;
  std::unique_ptr<ServerConnection> server_;
  protocol::StreamContext context_;
  uint32_t frame_ = 0;
  uint64_t splits_received_ = 0;         // over every session
  std::unique_ptr<HeldLeaves> held_;     // with LoadClientOptions::model
  // A session whose packets are split records decodes them against the hierarchy they make (what
  // ClientSession holds): ids, positions, refinement info and cut vertices, nothing of a mesh.
  std::unique_ptr<VertexHierarchy> hierarchy_;
};

}  // namespace pms::client
