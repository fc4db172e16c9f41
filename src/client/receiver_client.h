// The receiver-driven client (cheng-ooi 2008 §4; docs/protocol.md, "Receiver-driven over HTTP"): it decides
// what it needs and asks for it by id over stateless HTTP GETs, so the answers can come from any cache.
// It has no session (no HELLO, OPEN, VIEW), so it is a driver of its own beside StreamingClient rather than
// a ClientMode (docs/architecture.md, "Streaming modes"); it shares ClientSession and FrameReport with them.
#pragma once
#include <chrono>
#include <nlohmann/json.hpp>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "client/client_mode.h"
#include "client/client_session.h"
#include "client/http_connection.h"
#include "client/screen_importance.h"
#include "pm/split_codec.h"
#include "pm/vertex_id.h"
#include "protocol/split_request.h"
#include "refine/camera.h"

namespace pms::client {

// How the client turns the splits it lacks into URLs (docs/protocol.md, "Receiver-driven client").
enum class FetchPolicy : uint8_t {
  lists,   // GET /splits/{code}: exactly the ids it lacks, ids_per_request to a URL (per-client URLs)
  blocks,  // GET /blocks/{tree}/{node}/{depth}: the fixed subtree band holding each id (URLs shared by clients)
};
const char* fetch_policy_name(FetchPolicy policy);
// Throws pms::Error naming `where` for a name that is not "lists" or "blocks".
FetchPolicy fetch_policy_named(const std::string& name, const std::string& where = "--fetch");

struct ReceiverOptions {
  float tolerance = 1;
  uint32_t morph_frames = 0;
  uint32_t max_ops = 0;            // per frame, 0 = no cap
  FetchPolicy fetch = FetchPolicy::lists;
  uint32_t ids_per_request = 64;   // lists: split ids in one GET /splits/{code}
  uint32_t block_depth = 2;        // blocks: levels below a block's root; GET /models suggests the same
  HttpOptions http;                // deadlines, requests in flight, answer limits
  // Called after each answer's splits are attached, before the next answer is read (a progress display's
  // hook; the bench's E6 samples the mesh there). It may adapt the session's mesh; it must not fetch.
  std::function<void()> on_attached = {};
};

struct ReceiverFrame {
  FrameReport report;          // up/down bytes are on the wire, headers included
  uint64_t payload_down = 0;   // the answers' bodies alone
  uint32_t split_requests = 0; // GETs of split ids this frame
  uint32_t cache_hits = 0;     // of those, answers a cache in between served (X-Cache-Status: HIT)
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
  uint64_t cache_hits() const { return cache_hits_; }

 private:
  nlohmann::json catalogue();
  std::vector<VertexId> ranked_missing(const Camera& camera);
  struct Requests {
    std::vector<std::string> targets;               // the URLs, in the order they are sent
    std::vector<protocol::SplitRequest> requests;   // what each names: format 2's answers are read by it
  };
  Requests list_requests(const std::vector<VertexId>& ids) const;
  Requests block_requests(const std::vector<VertexId>& ids) const;
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
  uint64_t cache_hits_ = 0;
};

}  // namespace pms::client
