// The receiver-driven client (cheng-ooi 2008 §4; docs/protocol.md, "Receiver-driven over HTTP"): it decides
// what it needs and asks for it by id over stateless HTTP GETs, so the answers can come from any cache.
// It has no session (no HELLO, OPEN, VIEW), so it is a driver of its own beside StreamingClient rather than
// a ClientMode (docs/architecture.md, "Streaming modes"); it shares ClientSession and FrameReport with them.
#pragma once
#include <chrono>
#include <nlohmann/json.hpp>
#include <cstdint>
#include <string>
#include <vector>

#include "client/client_mode.h"
#include "client/client_session.h"
#include "client/http_connection.h"
#include "client/screen_importance.h"
#include "pm/split_codec.h"
#include "pm/vertex_id.h"
#include "refine/camera.h"

namespace pms::client {

struct ReceiverOptions {
  float tolerance = 1;
  uint32_t morph_frames = 0;
  uint32_t max_ops = 0;            // per frame, 0 = no cap
  uint32_t ids_per_request = 64;   // split ids in one GET /splits/{code}
  HttpOptions http;                // deadlines, requests in flight, answer limits
};

struct ReceiverFrame {
  FrameReport report;          // up/down bytes are on the wire, headers included
  uint64_t payload_down = 0;   // the answers' bodies alone
  uint32_t split_requests = 0; // GETs of split ids this frame
  uint32_t rounds = 0;         // adapt -> request -> attach cycles
};

class ReceiverClient {
 public:
  ReceiverClient(const HttpUrl& server, const ReceiverOptions& options = {});

  std::vector<std::string> list();   // GET /models: the names
  void open(const std::string& model);  // GET /models/{m}/base

  // One frame: adapt; while qrefine wants splits the client lacks, rank them by screen area, GET them
  // in that order with several requests in flight, attach what arrives, adapt again.
  ReceiverFrame frame(const Camera& camera);
  void settle(const Camera& camera);

  ClientSession& session() { return session_; }
  const HttpCounters& counters() const { return http_.counters(); }
  uint64_t split_requests() const { return split_requests_; }

 private:
  nlohmann::json catalogue();
  std::vector<VertexId> ranked_missing(const Camera& camera);
  size_t fetch(const std::vector<VertexId>& ids);

  ReceiverOptions options_;
  HttpConnection http_;
  ClientSession session_;
  ScreenImportance importance_;
  std::string model_;
  uint32_t records_format_ = 1;  // the catalogue's word for the model: 2 = compact records, coded by codec_
  SplitCodec codec_;
  uint32_t frame_ = 0;
  uint64_t split_requests_ = 0;
};

}  // namespace pms::client
