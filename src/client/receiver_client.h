// The receiver-driven client (cheng-ooi 2008 §4; docs/protocol.md, "Receiver-driven over HTTP"): it decides
// what it needs and asks for it by id over stateless HTTP GETs, so the answers can come from any cache.
// It has no session (no HELLO, OPEN, VIEW), so it is a driver of its own beside StreamingClient rather than
// a ClientMode (docs/architecture.md, "Streaming modes"); it shares ClientSession and FrameReport with them.
// No I/O of its own: answers in, targets out, over an HttpTransport.
#pragma once
#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "client/client_mode.h"
#include "client/client_session.h"
#include "client/http_transport.h"
#include "client/importance.h"
#include "client/model_version.h"
#include "common/camera.h"
#include "protocol/url_segment.h"
#include "protocol/split_request.h"
#include "spm/split_codec.h"
#include "spm/vertex_id.h"

namespace pms::client {

// How the client turns the splits it lacks into URLs (docs/protocol.md, "Receiver-driven client").
enum class FetchPolicy : uint8_t {
  lists,   // GET /splits/{code}: exactly the ids it lacks, ids_per_request to a URL (per-client URLs)
  blocks,  // GET /blocks/{tree}/{node}/{depth}: the fixed subtree band holding each id (URLs shared by clients)
};
const char* fetch_policy_name(FetchPolicy policy);
// Throws pms::Error naming `where` for a name that is not "lists" or "blocks".
FetchPolicy fetch_policy_named(const std::string& name, const std::string& where = "--fetch");

// What the client ranks the front's leaves by and how it decides it is done (docs/protocol.md,
// "Receiver-driven client"; docs/architecture.md says which properties each keeps).
enum class Ranking : uint8_t {
  // Screen area × squared screen error over the info form's records; qrefine (τ) decides what is wanted,
  // so the mesh is local refinement's for the view.
  error,
  // cheng-ooi 2008 §4.2, faithfully: screen area alone over the plain form's records (no spheres, cones or
  // errors on the wire); a leaf is wanted while its visible area is at least stop_area pixels, and every
  // split held is made. Its mesh is judged by PSNR, not by equality.
  area,
};
const char* ranking_name(Ranking ranking);
// Throws pms::Error naming `where` for a name that is not "error" or "area".
Ranking ranking_named(const std::string& name, const std::string& where = "--ranking");

struct ReceiverOptions {
  Ranking ranking = Ranking::error;
  uint32_t stop_area = 64;  // area ranking: pixels of visible faces below which a leaf is not split
  float tolerance = 1;
  uint32_t morph_frames = 0;
  uint32_t max_ops = 0;  // per frame, 0 = no cap
  uint32_t adapt_budget_us = 0;  // a frame's adaptation time (AdaptOptions::time_budget_us), 0 = no limit
  FetchPolicy fetch = FetchPolicy::lists;
  uint32_t ids_per_request = 64;  // lists: split ids in one GET /splits/{code}
  uint32_t block_depth = 2;       // blocks: levels below a block's root; GET /models suggests the same
  // lists: at most this many levels below a visible leaf whose screen error is many times τ come with it
  // (receiver_client.cpp, descendant_depth()); 0: the ids alone, exactly the splits the views want.
  uint32_t descendant_depth = 2;
  HttpOptions http;  // the HttpConnection made from a URL: deadlines, requests in flight, answer limits
  // The frame budget (docs/protocol.md, "Frame budget, cancel and prefetch"): with either set, a frame also ends once
  // it has read frame_answers answers or spent frame_budget_ms (checked between answers, so a frame overruns by at most
  // one answer; one answer is always read when one is due). The rest carries to the next frame: GETs sent stay in
  // flight and are read then, ids not yet sent stay queued and are re-ranked for the next view, which drops those it no
  // longer wants. Both 0: each frame runs until its view is satisfied.
  uint32_t frame_budget_ms = 0;
  uint32_t frame_answers = 0;
  // When the view's wants are all sent and the pipe has room, GET the splits the camera extrapolated from
  // the last two frames would want: ranked once a frame, sent as answers make room.
  bool prefetch = false;
  // cheng-ooi §4.2's refresh: the splits that arrive change what is visible even when the camera holds
  // still, so the front is ranked again at least this often. A ranking renders the mesh: free-running
  // frames rank only when the camera moved, when this is due, when the view options changed, or when the
  // queue is empty and the adaptation wants a split not asked for (answers revealed it); lock-step frames
  // rank as answers come (kRerankShare) and when this is due. 0: free-running frames rank every frame.
  uint32_t rerank_ms = 1000;
  // Free-running only (idle time is between frames): once the view wants nothing more and the prefetch has
  // nothing to ask, keep fetching the model's remaining splits, largest error first, at the lowest
  // priority, until their answers' bodies reach this many bytes (overrun by at most the GETs in flight).
  // They are held like prefetched splits: adapt() makes them only when a view wants them. 0: off.
  uint64_t background_bytes = 0;
  // frame() never waits for the network (the free-running viewer): it attaches the answers that have fully
  // arrived, re-ranks, hands the pipe what fits and returns; the frame budget does not apply. settle() then
  // waits for what the last view wants, and the mesh is local refinement's for it, as in lock-step.
  bool free_running = false;
  // Called after each answer's splits are attached, before the next answer is read (a progress display's
  // hook; the bench's E6 samples the mesh there). It may adapt the session's mesh; it must not fetch.
  std::function<void()> on_attached = {};
};

struct ReceiverFrame {
  FrameReport report;           // up/down bytes are on the wire, headers included
  uint64_t payload_down = 0;    // the answers' bodies alone
  uint32_t split_requests = 0;  // GETs of split ids this frame
  uint32_t cache_hits = 0;      // of those, answers a cache in between served (X-Cache-Status: HIT)
  uint32_t rounds = 0;          // rankings of the front that wanted something (adapt -> rank; answers come between)
  uint32_t rankings = 0;        // rankings of the front (each renders the mesh for the screen areas)
  uint32_t cancelled = 0;       // queued ids (blocks: block roots) dropped unsent: this view no longer wants them
  uint32_t stale_arrivals = 0;  // ids whose answers came after the view stopped wanting them (attached all the same)
  uint32_t prefetched = 0;      // ids asked for along the predicted path
  uint32_t prefetch_used = 0;   // prefetched ids whose splits the mesh has made by this frame's end
  uint32_t background = 0;      // ids asked for in the background (ReceiverOptions::background_bytes)
  uint32_t queued = 0;          // ids left queued at the frame's end
  uint32_t in_flight = 0;       // GETs left on the wire at the frame's end
  uint32_t answers = 0;         // answers attached this frame
  bool satisfied = true;        // the view wants nothing more: local refinement's mesh for it
};

// A client's counts since it opened the model.
struct ReceiverTotals {
  uint64_t split_requests = 0, cache_hits = 0;
  // Ids named by the split GETs sent (a block's root counts once) and, for lists, the bytes of their id
  // sets' codes before base64url (docs/protocol.md, "Split request code"): the bits per requested id.
  uint64_t requested_ids = 0, request_code_bytes = 0;
  uint64_t cancelled = 0, stale_arrivals = 0, prefetched = 0, prefetch_used = 0;
  uint64_t rankings = 0;
  uint64_t background_ids = 0, background_bytes = 0;  // asked for in the background; their answers' bodies
};

class ReceiverClient {
 public:
  // Over `http` (the native HttpConnection, the browser's fetch, a test's), ranking the front by `importance`.
  ReceiverClient(std::unique_ptr<HttpTransport> http, std::unique_ptr<ImportanceSource> importance,
                 const ReceiverOptions& options = {});
  // The native build's (native_http_clients.cpp): ranking with the software renderer (ScreenImportance),
  // over `http` or over an HttpConnection to `server` with options.http.
  ReceiverClient(std::unique_ptr<HttpTransport> http, const ReceiverOptions& options = {});
  ReceiverClient(const HttpUrl& server, const ReceiverOptions& options = {});

  std::vector<std::string> list();      // GET /models: the names
  // GET /models for the model's version, then its base and code tables (docs/protocol.md, "Versions"). A
  // 410 later (the model replaced under its name) drops the mesh and opens the version it names: the frame
  // goes on with it (lock-step), or the next frames report opening until it is open (free-running).
  void open(const std::string& model);
  // The same without waiting (the browser's): start_open() posts the GETs, each poll_open() takes what has
  // arrived, until it returns true: the model is open. frame() is for after that.
  void start_open(const std::string& model);
  bool poll_open();

  // One frame: adapt; while qrefine wants splits the client lacks, rank them by screen area × squared
  // screen error (the area ranking: while leaves cover the stop area, by screen area alone), GET them in that
  // order with several requests in flight, attach what arrives, adapt and rank again as answers come; within
  // the frame budget, if any.
  ReceiverFrame frame(const Camera& camera);
  // Holds the last camera for frames (within the budget, without prefetch) until its view is satisfied,
  // then reads what is still in flight and converges. settle_frames(): how many it took (1 unbudgeted).
  void settle(const Camera& camera);
  // New tolerance, geomorph length, prefetch, refresh period and idle-fetch budget from `options` (the
  // rest of it is ignored): the next frame ranks, refines and fetches by them, the mesh is kept.
  void set_view_options(const ReceiverOptions& options);
  uint32_t settle_frames() const { return settle_frames_; }

  ClientSession& session() { return session_; }
  const HttpCounters& counters() const { return http_->counters(); }
  const ReceiverTotals& totals() const { return totals_; }
  uint64_t split_requests() const { return totals_.split_requests; }
  uint64_t cache_hits() const { return totals_.cache_hits; }
  uint64_t reopens() const { return reopens_.total(); }  // versions opened after a 410
  const std::string& version() const { return version_; }  // the model's version open (or opening)

 private:
  // Why a GET was sent, most urgent first: the view's wants, the extrapolated view's, the idle fetch's.
  enum class Source : uint8_t { view, prefetch, background };
  // One GET: its URL and the ids it names (lists: the ids; blocks: the block's root).
  struct Request {
    std::string target;
    protocol::SplitRequest request;  // format 3's answers are read by it
    uint32_t code_bytes = 0;         // lists: the id set's code in the target, before base64url
    Source source = Source::view;
    bool wanted = true;              // the last ranking wants one of its ids
    uint32_t stale = 0;              // of its ids, those the last ranking no longer wants (view GETs only)
  };
  std::string prefix() const { return protocol::model_path(model_, version_); }
  // Where the records of the form this client reads are: the plain form's under /plain.
  std::string records_prefix() const;
  void open_version(const nlohmann::json& entry);
  void await_open();
  void replaced(const std::string& target, const HttpAnswer& answer);
  void opened(const std::vector<std::string>& targets, const std::vector<HttpAnswer>& answers);
  ReceiverFrame begin(const Camera& camera);
  void finish(ReceiverFrame& out, const HttpCounters& before, const ReceiverTotals& totals_before);
  ReceiverFrame run(const Camera& camera, bool settling);
  ReceiverFrame run_free(const Camera& camera, bool settling);
  void settle_locked(const Camera& camera);
  void settle_free(const Camera& camera);
  // A leaf to ask for and the descendant depth to ask for it with (lists).
  struct Wanted {
    VertexId id;
    uint32_t depth = 0;
  };
  std::vector<Wanted> ranked(std::span<const uint32_t> slots, const ViewParams& view);
  std::vector<Wanted> ranked_by_area(std::span<const uint32_t> slots, const ViewParams& view);
  uint32_t descendant_depth(float priority, float pixel_angle2) const;
  VertexId key(VertexId id) const;
  std::vector<VertexId> keys_on_wire() const;
  std::vector<Request> requests_for(const std::vector<Wanted>& ids) const;
  std::vector<Request> list_requests(const std::vector<Wanted>& ids) const;
  Request list_request(std::vector<VertexId> ids, uint32_t depth) const;
  size_t list_size(uint32_t depth) const;
  std::vector<Request> block_requests(const std::vector<Wanted>& ids) const;
  bool rerank(const Camera& camera);
  bool rank(const Camera& camera);
  bool wants_unasked();
  bool ranking_due() const;
  bool round_open() const;
  size_t queued_ids() const;
  bool over_budget(uint32_t answers, std::chrono::steady_clock::time_point start) const;
  void fill_pipe(bool may_prefetch, bool may_background);
  bool send_from(std::deque<Request>& planned, Source source);
  bool still_lacked(Request& request, const std::vector<VertexId>& on_wire);
  void send(Request&& request);
  size_t receive_one(ReceiverFrame& out);
  size_t attach(const HttpAnswer& answer, ReceiverFrame& out);
  size_t attach_arrived(ReceiverFrame& out);
  std::vector<uint32_t> leaves_wanted(const ViewParams& view);
  std::deque<Request> plan_prefetch();
  std::deque<Request> plan_background();
  uint32_t count_prefetch_used();

  // A frame re-ranks once the splits attached since its last ranking reach 1/kRerankShare of the ids queued
  // (and ids_per_request), or nothing is queued.
  static constexpr size_t kRerankShare = 16;
  ReceiverOptions options_;
  std::unique_ptr<HttpTransport> http_;
  ClientSession session_;
  std::unique_ptr<ImportanceSource> importance_;
  std::string model_;
  std::string version_;  // the version open, or opening
  // The GETs of an open (GET /models alone, then a version's base and tables), until poll_open() has them.
  std::unique_ptr<PendingGets> opening_;
  ReopenBudget reopens_;
  SplitCodec codec_;  // the model's split record tables (GET /models/{m}/codec)
  uint32_t frame_ = 0;
  uint32_t settle_frames_ = 0;
  ReceiverTotals totals_;
  std::deque<Request> queue_;  // ranked for the last view, not yet sent
  std::deque<Request> wire_;   // sent, in the order their answers come
  // Lower priorities, sent only while queue_ is empty, each checked again when sent (its ids may have
  // arrived or gone on the wire meanwhile): the extrapolated view's, ranked once a frame; the idle fetch's,
  // planned in bounded batches and kept until sent.
  std::deque<Request> prefetch_queue_;
  bool prefetch_planned_ = false;
  std::deque<Request> background_queue_;
  // The last ranking: its camera (none: the next frame ranks) and time.
  std::optional<Camera> ranked_camera_;
  std::chrono::steady_clock::time_point ranked_at_{};
  // Prefetched ids whose splits the mesh has not made yet: each id at most once (it is a leaf until its
  // answer comes, and on the wire till then), so bounded by the model's splits.
  std::vector<VertexId> prefetched_;
  std::vector<Camera> cameras_;  // the last two frames' (prefetch extrapolates them)
};

}  // namespace pms::client
