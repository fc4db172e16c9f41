// The receiver-driven client (receiver_client.h): the sender-driven client's frame loop, with the client
// choosing the splits itself — the leaves qrefine wants split, largest screen area × squared screen error
// first — and fetching them by id with the cacheable GET form. With a frame budget it keeps, between
// frames, the ranked ids not yet sent and the GETs on the wire; each view ranks the queue anew (cheng-ooi
// §4.2) and drops what it no longer wants, and spare room in the pipe goes to the extrapolated next view's
// splits (prefetch).
#include "client/receiver_client.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <utility>

#include "common/bit_stream.h"
#include "common/error.h"
#include "protocol/base64url.h"
#include "protocol/server_messages.h"
#include "protocol/split_request.h"
#include "protocol/url_segment.h"
#include "spm/adapt.h"
#include "spm/criteria.h"

namespace pms::client {
namespace {

// Frames without a cap reach the view's mesh for what is known in one adapt(); the extra passes only
// finish collapses that waited for a geomorph (as the sender-driven client does).
void adapt_for_view(SelectiveRefinement& refinement) {
  FrameStats stats = refinement.adapt();
  for (int pass = 0; pass < 64 && !stats.capped && stats.ops() > 0 && refinement.missing().empty(); ++pass)
    stats = refinement.adapt();
}

bool same_camera(const Camera& a, const Camera& b) {
  return std::equal(a.eye, a.eye + 3, b.eye) && std::equal(a.target, a.target + 3, b.target) &&
         std::equal(a.up, a.up + 3, b.up) && a.fovy_deg == b.fovy_deg && a.width == b.width && a.height == b.height;
}

// Appended piece by piece: GCC 12 warns wrongly (-Wrestrict) on a chain of `+` with to_string().
std::string block_target(const std::string& prefix, VertexId root, uint32_t depth) {
  std::string target = prefix;
  target += "/blocks/";
  target += std::to_string(root.tree);
  target += '/';
  target += std::to_string(root.node);
  target += '/';
  target += std::to_string(depth);
  return target;
}

// The area ranking's options: its own stop rule, and no prediction or idle fetch, whose choices follow
// qrefine, which plain records give no input for.
void check_area_options(const ReceiverOptions& options) {
  if (options.ranking != Ranking::area) return;
  if (options.stop_area == 0) fail("receiver", "the area ranking's stop area must be at least 1 pixel");
  if (options.prefetch || options.background_bytes > 0)
    fail("receiver", "the area ranking has no prefetch or idle fetch (they choose splits by qrefine)");
}

bool serves_plain_form(const nlohmann::json& entry) {
  const auto forms = entry.find("record_forms");
  if (forms == entry.end() || !forms->is_array()) return false;
  return std::any_of(forms->begin(), forms->end(), [](const nlohmann::json& f) { return f == "plain"; });
}

// The area ranking holds the roots as it holds a plain record's children (plain_split_info()): a root
// whose info can refine has a split and is made whatever the view; one whose info never refines stays a
// leaf, as nothing on the wire says whether it has a split.
void hold_roots_plain(protocol::Base& base) {
  for (RefineInfo& info : base.refine)
    if (!never_refines(info)) info = plain_split_info();
}

}  // namespace

const char* fetch_policy_name(FetchPolicy policy) { return policy == FetchPolicy::blocks ? "blocks" : "lists"; }

FetchPolicy fetch_policy_named(const std::string& name, const std::string& where) {
  if (name == "lists") return FetchPolicy::lists;
  if (name == "blocks") return FetchPolicy::blocks;
  fail(where, "'" + name + "' is not a fetch policy (lists or blocks)");
}

const char* ranking_name(Ranking ranking) { return ranking == Ranking::area ? "area" : "error"; }

Ranking ranking_named(const std::string& name, const std::string& where) {
  if (name == "error") return Ranking::error;
  if (name == "area") return Ranking::area;
  fail(where, "'" + name + "' is not a ranking (error or area)");
}

ReceiverClient::ReceiverClient(std::unique_ptr<HttpTransport> http, std::unique_ptr<ImportanceSource> importance,
                               const ReceiverOptions& options)
    : options_(options), http_(std::move(http)), importance_(std::move(importance)) {
  if (!http_ || !importance_) fail("receiver", "no transport or no importance source");
  if (options.ids_per_request == 0) fail("receiver", "ids_per_request must be at least 1");
  if (options.block_depth > 8) fail("receiver", "block_depth must be at most 8 (the server's request depth limit)");
  if (options.descendant_depth > 8)
    fail("receiver", "descendant_depth must be at most 8 (the server's request depth limit)");
  check_area_options(options);
  session_.adapt_options.tolerance = options.tolerance;
  session_.adapt_options.morph_frames = options.morph_frames;
  session_.adapt_options.max_ops = options.max_ops;
  session_.adapt_options.time_budget_us = options.adapt_budget_us;
  session_.refinement_info = true;  // the records carry the children's refinement info: the client refines
}

void ReceiverClient::set_view_options(const ReceiverOptions& options) {
  options_.tolerance = options.tolerance;
  options_.morph_frames = options.morph_frames;
  options_.prefetch = options.prefetch;
  options_.rerank_ms = options.rerank_ms;
  ranked_camera_.reset();  // the next frame ranks by the new options
  options_.background_bytes = options.background_bytes;
  check_area_options(options_);
  AdaptOptions adapt = session_.adapt_options;
  adapt.tolerance = options.tolerance;
  adapt.morph_frames = options.morph_frames;
  session_.set_adapt_options(adapt);
}

std::vector<std::string> ReceiverClient::list() {
  std::vector<std::string> names;
  for (const nlohmann::json& model : catalogue_models(http_->get("/models")))
    if (model.is_object() && model.contains("name") && model["name"].is_string())
      names.push_back(model["name"].get<std::string>());
  return names;
}

std::string ReceiverClient::records_prefix() const {
  return options_.ranking == Ranking::area ? prefix() + "/plain" : prefix();
}

// Its version from GET /models, then the base and the code tables of that version in one round trip.
void ReceiverClient::open(const std::string& model) {
  if (session_.has_model() || opening_) fail("open", "this client already holds '" + model_ + "'");
  model_ = model;
  open_version(catalogue_entry(http_->get("/models"), model_));
  await_open();
}

// Waits for the version being opened (free-running: the transport's non-blocking calls, as frames use it).
void ReceiverClient::await_open() {
  if (options_.free_running) {
    while (!poll_open()) http_->wait();
    return;
  }
  while (!wire_.empty()) {  // the replaced version's
    http_->receive();
    wire_.pop_front();
  }
  while (opening_) {  // again after a 410 in its answers
    const std::unique_ptr<PendingGets> done = std::move(opening_);
    opened(done->targets(), http_->get_all(done->targets()));
  }
}

void ReceiverClient::start_open(const std::string& model) {
  if (session_.has_model() || opening_) fail("open", "this client already holds '" + model_ + "'");
  model_ = model;
  opening_ = std::make_unique<PendingGets>(std::vector<std::string>{"/models"});
}

// The catalogue (when the version is not known yet), then the version's base and tables; first, after a
// 410, the answers of the replaced version still on the wire, read and dropped.
bool ReceiverClient::poll_open() {
  if (session_.has_model()) return true;
  if (!opening_) fail("open", "no model being opened");
  http_->poll();
  while (!wire_.empty()) {
    if (!http_->take()) return false;
    wire_.pop_front();
  }
  if (!opening_->advance(*http_)) return false;
  const std::unique_ptr<PendingGets> done = std::move(opening_);
  if (done->targets().size() == 1) {
    open_version(catalogue_entry(done->answers()[0], model_));
    return poll_open();
  }
  opened(done->targets(), done->answers());
  return poll_open();  // true, unless a 410 there started another re-open
}

// Opens the version `entry` names once its base and tables arrive (poll_open).
void ReceiverClient::open_version(const nlohmann::json& entry) {
  // The body format of the answers (docs/protocol.md, "Receiver-driven over HTTP"): compact split records.
  constexpr uint32_t kRecordsFormat = 4;
  const uint32_t records_format = entry.value("records_format", 0u);
  if (records_format != kRecordsFormat)
    fail("GET /models", "records format " + std::to_string(records_format) + " is not one this client reads (" +
                            std::to_string(kRecordsFormat) + ")");
  if (options_.ranking == Ranking::area && !serves_plain_form(entry))
    fail("GET /models", "the server does not serve the plain record form the area ranking reads");
  version_ = entry_version(entry);
  opening_ = std::make_unique<PendingGets>(std::vector<std::string>{prefix() + "/base", records_prefix() + "/codec"});
}

// A 410: the model was replaced under its name. The held mesh belongs to the old version: it is dropped
// with everything queued, and the version the 410 names opens as a new model (poll_open), the answers
// still on the wire read and dropped first.
void ReceiverClient::replaced(const std::string& target, const HttpAnswer& answer) {
  const nlohmann::json entry = reopens_.follow(target, answer, model_);
  queue_.clear();
  prefetch_queue_.clear();
  background_queue_.clear();
  prefetched_.clear();
  cameras_.clear();
  ranked_camera_.reset();
  const AdaptOptions adapt = session_.adapt_options;
  session_ = ClientSession();
  session_.adapt_options = adapt;
  session_.refinement_info = true;
  open_version(entry);
}

void ReceiverClient::opened(const std::vector<std::string>& targets, const std::vector<HttpAnswer>& answers) {
  for (size_t i = 0; i < answers.size(); ++i)
    if (answers[i].status == 410) return replaced(targets[i], answers[i]);
  const std::string& target = targets[0];
  const std::string& tables = targets[1];
  const HttpAnswer& answer = answers[0];
  if (answer.status != 200) refused(target, answer);
  protocol::Base base_read = protocol::decode_base(answer.body);
  if (options_.ranking == Ranking::area) hold_roots_plain(base_read);
  session_.on_base(base_read);
  const HttpAnswer& codec = answers[1];
  if (codec.status != 200) refused(tables, codec);
  BitReader r(codec.body, "GET " + tables);
  codec_ = SplitCodec::deserialize(r);
  const protocol::Base& base = session_.base();
  if (codec_.root_count() != base.root_count() || codec_.position_bits() != session_.context().grid.bits ||
      codec_.has_normals() != base.has_normals || codec_.has_colors() != base.has_colors)
    fail("GET " + tables, "code tables of another model, grid or attributes than its BASE");
  const RecordForm form = options_.ranking == Ranking::area ? RecordForm::plain : RecordForm::info;
  if (codec_.form() != form)
    fail("GET " + tables, std::string("code tables of the ") + record_form_name(codec_.form()) + " form, not the " +
                              record_form_name(form) + " form");
}

// `slots` (leaves the client holds) as ids: the visible ones by the squared image error their splits may
// remove, then the rest (forced chains' leaves can be out of sight) in the order given. That error is the
// pixels of a vertex's faces as `view` sees the mesh (cheng-ooi §4.2) times its squared screen-space error
// (refinement_priority, what qrefine compares with τ): by pixels alone a large area a fraction of a pixel
// off would go before a smaller one many pixels off, which the PM order fixes first. Each visible one comes
// with the descendant depth to ask for it with (descendant_depth()).
std::vector<ReceiverClient::Wanted> ReceiverClient::ranked(std::span<const uint32_t> slots, const ViewParams& view) {
  if (options_.ranking == Ranking::area) return ranked_by_area(slots, view);
  std::vector<uint32_t> sorted(slots.begin(), slots.end());
  std::sort(sorted.begin(), sorted.end());
  sorted.erase(std::unique(sorted.begin(), sorted.end()), sorted.end());
  const auto wanted = [&sorted](uint32_t slot) { return std::binary_search(sorted.begin(), sorted.end(), slot); };
  const std::vector<VertexArea>& by_area = importance_->rank(session_.mesh(), view, wanted);
  VertexHierarchy& hierarchy = session_.hierarchy();
  const ViewCriteria criteria = make_criteria(view, options_.tolerance);
  const float pixel_angle2 = make_criteria(view, 1).kappa2;
  const float scale = session_.base().scale;
  struct ByError {
    double error;  // pixels times the squared screen-space error
    uint32_t slot;
    uint32_t depth;
  };
  std::vector<ByError> by_error;
  by_error.reserve(by_area.size());
  for (const VertexArea& area : by_area) {
    const NodeCriteria node =
        node_criteria(hierarchy.position(area.slot), dequantize_refine(hierarchy.refine(area.slot), scale));
    const float priority = refinement_priority(criteria, node);
    by_error.push_back({double(area.pixels) * double(priority), area.slot, descendant_depth(priority, pixel_angle2)});
  }
  std::stable_sort(by_error.begin(), by_error.end(),
                   [](const ByError& a, const ByError& b) { return a.error > b.error; });
  std::vector<uint8_t> taken(sorted.size(), 0);
  std::vector<Wanted> ids;
  ids.reserve(sorted.size());
  for (const ByError& e : by_error) {
    taken[size_t(std::lower_bound(sorted.begin(), sorted.end(), e.slot) - sorted.begin())] = 1;
    ids.push_back({hierarchy.id(e.slot), e.depth});
  }
  for (const uint32_t slot : slots) {
    const size_t at = size_t(std::lower_bound(sorted.begin(), sorted.end(), slot) - sorted.begin());
    if (taken[at]) continue;
    taken[at] = 1;
    ids.push_back({hierarchy.id(slot), 0});
  }
  return ids;
}

// cheng-ooi §4.2's ranking: the leaves of `slots` whose faces cover at least stop_area pixels as `view` sees
// the mesh, most pixels first, then the leaves forced chains stopped at (the splits those depend on, which
// the client fetches whatever their area: the partial order holds as in the error ranking). A leaf with no
// visible face (a root of no face, one out of sight) has no area and is not asked for. Each comes with
// descendants while its area is many times the stop area (cheng-ooi §4.3): one level more per quadrupling
// beyond 4×, as a split's children share its area.
std::vector<ReceiverClient::Wanted> ReceiverClient::ranked_by_area(std::span<const uint32_t> slots,
                                                                   const ViewParams& view) {
  std::vector<uint32_t> sorted(slots.begin(), slots.end());
  std::sort(sorted.begin(), sorted.end());
  sorted.erase(std::unique(sorted.begin(), sorted.end()), sorted.end());
  const auto in_slots = [&sorted](uint32_t slot) { return std::binary_search(sorted.begin(), sorted.end(), slot); };
  const std::vector<VertexArea>& by_area = importance_->rank(session_.mesh(), view, in_slots);
  const VertexHierarchy& hierarchy = session_.hierarchy();
  std::vector<uint8_t> taken(sorted.size(), 0);
  const auto take = [&](uint32_t slot) {
    uint8_t& t = taken[size_t(std::lower_bound(sorted.begin(), sorted.end(), slot) - sorted.begin())];
    return !std::exchange(t, uint8_t(1));
  };
  std::vector<Wanted> ids;
  for (const VertexArea& area : by_area) {
    if (area.pixels < options_.stop_area) break;  // most pixels first: the rest are smaller
    const double ratio = double(area.pixels) / double(options_.stop_area);
    const int quadruplings = std::ilogb(ratio) / 2;
    take(area.slot);
    ids.push_back({hierarchy.id(area.slot), uint32_t(std::clamp(quadruplings - 1, 0, int(options_.descendant_depth)))});
  }
  for (const uint32_t slot : session_.refinement().forced_missing())
    if (in_slots(slot) && take(slot)) ids.push_back({hierarchy.id(slot), 0});
  return ids;
}

// cheng-ooi §4.3's descendant depth for a visible leaf whose screen-space error is many times τ (at least
// 4·max(τ, 1) px): its children will most likely be wanted too, so its GET brings them with it, one level
// more per doubling of the error beyond that, at most options.descendant_depth. A level down the front
// then costs no wait for an answer (with several GETs in flight, a pipe-full of other splits' bytes). The
// 1 px floor keeps it to errors whose children are large enough to show. A descendant the view turns out
// not to want is held like a prefetched split: adapt() makes it only when a view wants it.
uint32_t ReceiverClient::descendant_depth(float priority, float pixel_angle2) const {
  if (options_.descendant_depth == 0 || !(priority > 0) || !(pixel_angle2 > 0)) return 0;
  const float floor_px = std::max(options_.tolerance, 1.0f);
  // floor(log2(r) / 2) is floor(floor(log2 r) / 2), and ilogb gives floor(log2 r) exactly on every
  // platform, where log2 itself may round differently in the browser's libm.
  const double ratio = double(priority) / (double(pixel_angle2) * floor_px * floor_px);
  if (!(ratio >= 1)) return 0;  // and NaN; ilogb(inf) is INT_MAX: the whole depth
  const int doublings = std::ilogb(ratio) / 2;
  return uint32_t(std::clamp(doublings - 1, 0, int(options_.descendant_depth)));
}

// What a GET names for `id`: the id itself (lists) or the root of the block holding it (blocks).
VertexId ReceiverClient::key(VertexId id) const {
  if (options_.fetch == FetchPolicy::lists) return id;
  const int band = int(options_.block_depth) + 1;
  return ancestor_at_depth(id, id.depth() / band * band);
}

// The ids the GETs on the wire name, in code order.
std::vector<VertexId> ReceiverClient::keys_on_wire() const {
  std::vector<VertexId> keys;
  for (const Request& sent : wire_) keys.insert(keys.end(), sent.request.ids.begin(), sent.request.ids.end());
  std::sort(keys.begin(), keys.end(), protocol::code_order);
  return keys;
}

std::vector<ReceiverClient::Request> ReceiverClient::requests_for(const std::vector<Wanted>& ids) const {
  return options_.fetch == FetchPolicy::blocks ? block_requests(ids) : list_requests(ids);
}

// Lists of ids with one descendant depth each, in the rank order of their first ids: ids_per_request >> depth
// ids to a URL (an answer holds about as many splits at each depth); each URL is the code of its id set.
std::vector<ReceiverClient::Request> ReceiverClient::list_requests(const std::vector<Wanted>& ids) const {
  std::vector<std::pair<size_t, Request>> lists;                      // (rank of the first id, request)
  std::vector<size_t> open(options_.descendant_depth + 1, SIZE_MAX);  // per depth: the list being filled
  for (size_t rank = 0; rank < ids.size(); ++rank) {
    const uint32_t depth = ids[rank].depth;
    if (open[depth] == SIZE_MAX) {
      open[depth] = lists.size();
      lists.emplace_back(rank, Request{}).second.request.depth = depth;
    }
    std::vector<VertexId>& list = lists[open[depth]].second.request.ids;
    list.push_back(ids[rank].id);
    if (list.size() >= list_size(depth)) open[depth] = SIZE_MAX;
  }
  std::vector<Request> out;
  out.reserve(lists.size());
  for (auto& [rank, r] : lists) out.push_back(list_request(std::move(r.request.ids), r.request.depth));
  return out;
}

// The GET of `ids` with `depth` levels below each: the URL is the code of the id set.
ReceiverClient::Request ReceiverClient::list_request(std::vector<VertexId> ids, uint32_t depth) const {
  Request r;
  r.request.depth = depth;
  r.request.ids = std::move(ids);
  // The answer comes in code order, which the bands are read in.
  std::sort(r.request.ids.begin(), r.request.ids.end(), protocol::code_order);
  const std::vector<uint8_t> code = protocol::encode_split_request(r.request);
  r.code_bytes = uint32_t(code.size());
  r.target = records_prefix() + "/splits/" + protocol::base64url_encode(code);
  return r;
}

size_t ReceiverClient::list_size(uint32_t depth) const {
  return std::max<size_t>(1, options_.ids_per_request >> depth);
}

// The block of each id (its ancestor at the top of its band of block_depth + 1 levels), in the rank order
// of the first id that needs it. An id the client lacks is a leaf of what it holds; the splits of its band
// above it would have come with its own block, so the id is that block's root, a vertex the client has,
// and no block is fetched twice (it would have brought the id): no record arrives twice. A block's answer is that of
// the request "its root, block_depth levels down", which is how the bands are read.
std::vector<ReceiverClient::Request> ReceiverClient::block_requests(const std::vector<Wanted>& ids) const {
  std::set<std::pair<uint32_t, uint64_t>> asked;
  std::vector<Request> out;
  for (const Wanted& wanted : ids) {
    const VertexId root = key(wanted.id);
    if (!asked.emplace(root.tree, root.node).second) continue;
    Request& r = out.emplace_back();
    r.target = block_target(records_prefix(), root, options_.block_depth);
    r.request = {options_.block_depth, {root}};
  }
  return out;
}

// Adapts to the view set and ranks what it wants anew (cheng-ooi §4.2): the GETs on the wire learn whether
// this view still wants their ids (HTTP/1.1 cannot take them back: their answers are read and attached, the
// unwanted ids counted as stale arrivals), and the queue becomes this view's wants not on the wire, in rank
// order. Ids queued for an earlier view that this one does not want are dropped unsent: the cancel. Returns
// whether the view wants anything it does not hold.
bool ReceiverClient::rerank(const Camera& camera) {
  adapt_for_view(session_.refinement());
  return rank(camera);
}

// rerank() after the adaptation.
bool ReceiverClient::rank(const Camera& camera) {
  SelectiveRefinement& refinement = session_.refinement();
  ranked_camera_ = camera;
  ranked_at_ = std::chrono::steady_clock::now();
  ++totals_.rankings;
  std::vector<Wanted> ids = ranked(refinement.missing(), session_.view_params(camera));
  std::vector<VertexId> wanted;
  wanted.reserve(ids.size());
  for (const Wanted& w : ids) wanted.push_back(key(w.id));
  std::sort(wanted.begin(), wanted.end(), protocol::code_order);
  const auto in = [](const std::vector<VertexId>& set, VertexId id) {
    return std::binary_search(set.begin(), set.end(), id, protocol::code_order);
  };
  for (Request& sent : wire_) {
    const auto unwanted = uint32_t(
        std::count_if(sent.request.ids.begin(), sent.request.ids.end(), [&](VertexId id) { return !in(wanted, id); }));
    sent.wanted = unwanted < sent.request.ids.size();
    if (sent.source == Source::view) sent.stale = unwanted;
  }
  const std::vector<VertexId> on_wire = keys_on_wire();
  std::erase_if(ids, [&](const Wanted& w) { return in(on_wire, key(w.id)); });
  std::vector<Request> queue = requests_for(ids);
  std::vector<VertexId> queued;
  for (const Request& r : queue) queued.insert(queued.end(), r.request.ids.begin(), r.request.ids.end());
  std::sort(queued.begin(), queued.end(), protocol::code_order);
  for (const Request& r : queue_)
    totals_.cancelled += uint64_t(
        std::count_if(r.request.ids.begin(), r.request.ids.end(), [&](VertexId id) { return !in(queued, id); }));
  queue_.assign(std::make_move_iterator(queue.begin()), std::make_move_iterator(queue.end()));
  return round_open();
}

// The adaptation wants a split that is neither queued nor on the wire (answers revealed it, a paused walk
// went on, the tolerance changed).
bool ReceiverClient::wants_unasked() {
  const std::span<const uint32_t> missing = session_.refinement().missing();
  if (missing.empty()) return false;
  std::vector<VertexId> asked = keys_on_wire();
  for (const Request& r : queue_) asked.insert(asked.end(), r.request.ids.begin(), r.request.ids.end());
  std::sort(asked.begin(), asked.end(), protocol::code_order);
  const VertexHierarchy& hierarchy = session_.hierarchy();
  return std::any_of(missing.begin(), missing.end(), [&](uint32_t slot) {
    return !std::binary_search(asked.begin(), asked.end(), key(hierarchy.id(slot)), protocol::code_order);
  });
}

bool ReceiverClient::ranking_due() const {
  return std::chrono::steady_clock::now() - ranked_at_ >= std::chrono::milliseconds(options_.rerank_ms);
}

size_t ReceiverClient::queued_ids() const {
  size_t ids = 0;
  for (const Request& r : queue_) ids += r.request.ids.size();
  return ids;
}

// The view wants something not in yet: queued, or on the wire.
bool ReceiverClient::round_open() const {
  return !queue_.empty() || std::any_of(wire_.begin(), wire_.end(), [](const Request& sent) { return sent.wanted; });
}

bool ReceiverClient::over_budget(uint32_t answers, std::chrono::steady_clock::time_point start) const {
  if (options_.frame_answers != 0 && answers >= options_.frame_answers) return true;
  return options_.frame_budget_ms != 0 &&
         std::chrono::steady_clock::now() - start >= std::chrono::milliseconds(options_.frame_budget_ms);
}

void ReceiverClient::send(Request&& request) {
  if (options_.free_running) http_->post(request.target);
  else http_->send(request.target);
  if (request.source == Source::prefetch) {
    prefetched_.insert(prefetched_.end(), request.request.ids.begin(), request.request.ids.end());
    totals_.prefetched += request.request.ids.size();
  } else if (request.source == Source::background) {
    totals_.background_ids += request.request.ids.size();
  }
  ++totals_.split_requests;
  totals_.requested_ids += request.request.ids.size();
  totals_.request_code_bytes += request.code_bytes;
  wire_.push_back(std::move(request));
}

// The queue's head onto the wire while the pipe has room; with the queue empty, the prefetch's (planned
// once a frame) and then the idle fetch's, within its byte budget. A list shorter than a full GET waits
// while an answer is due: that answer's splits are ranked with it, and fill it, instead of paying a header
// of their own.
void ReceiverClient::fill_pipe(bool may_prefetch, bool may_background) {
  while (http_->room() > 0) {
    if (!queue_.empty()) {
      const protocol::SplitRequest& head = queue_.front().request;
      const bool short_list = options_.fetch == FetchPolicy::lists && head.ids.size() < list_size(head.depth);
      if (short_list && !wire_.empty()) return;
      send(std::move(queue_.front()));
      queue_.pop_front();
      continue;
    }
    if (may_prefetch) {
      if (!prefetch_planned_) {
        prefetch_queue_ = plan_prefetch();
        prefetch_planned_ = true;
      }
      if (send_from(prefetch_queue_, Source::prefetch)) continue;
    }
    if (!may_background || totals_.background_bytes >= options_.background_bytes) return;
    if (background_queue_.empty()) background_queue_ = plan_background();
    if (!send_from(background_queue_, Source::background)) return;
  }
}

// Sends the first of `planned` that still names something lacked, dropping those before it. Returns
// whether one went.
bool ReceiverClient::send_from(std::deque<Request>& planned, Source source) {
  const std::vector<VertexId> on_wire = keys_on_wire();
  while (!planned.empty()) {
    Request request = std::move(planned.front());
    planned.pop_front();
    if (!still_lacked(request, on_wire)) continue;
    request.source = source;
    request.wanted = false;
    send(std::move(request));
    return true;
  }
  return false;
}

// A planned GET, trimmed to the ids whose splits are still lacked and not asked for on the wire (lists: the
// URL made again for what is left; a block's root is lacked or not). False when nothing is left. This is
// what keeps every record arriving once when a ranking or an answer overtook the plan.
bool ReceiverClient::still_lacked(Request& request, const std::vector<VertexId>& on_wire) {
  const VertexHierarchy& hierarchy = session_.hierarchy();
  const auto lacked = [&](VertexId id) {
    const uint32_t slot = hierarchy.find(id);
    return slot != kNone && hierarchy.is_leaf(slot) &&
           !std::binary_search(on_wire.begin(), on_wire.end(), key(id), protocol::code_order);
  };
  std::vector<VertexId>& ids = request.request.ids;
  if (std::all_of(ids.begin(), ids.end(), lacked)) return true;
  std::erase_if(ids, [&](VertexId id) { return !lacked(id); });
  if (ids.empty()) return false;
  request = list_request(std::move(ids), request.request.depth);  // a block names one id: never here
  return true;
}

// Reads the oldest answer due and attaches its splits. Returns the splits attached.
size_t ReceiverClient::receive_one(ReceiverFrame& out) { return attach(http_->receive(), out); }

// Every answer that has fully arrived, without waiting for one. Returns the splits attached.
size_t ReceiverClient::attach_arrived(ReceiverFrame& out) {
  size_t attached = 0;
  while (const std::optional<HttpAnswer> answer = http_->take()) attached += attach(*answer, out);
  return attached;
}

// The event "an answer arrived" (the oldest GET on the wire's): its splits attached, no I/O. Returns how many.
size_t ReceiverClient::attach(const HttpAnswer& answer, ReceiverFrame& out) {
  const Request sent = std::move(wire_.front());
  wire_.pop_front();
  if (opening_) return 0;  // an answer of a version replaced meanwhile
  if (answer.status == 410) {
    replaced(sent.target, answer);
    return 0;
  }
  if (answer.status != 200) refused(sent.target, answer);
  reopens_.refill();
  totals_.cache_hits += answer.cache_status == "HIT";
  totals_.stale_arrivals += sent.stale;
  if (sent.source == Source::background) totals_.background_bytes += answer.body.size();
  const size_t attached = session_.on_split_bands(answer.body, sent.request, codec_);
  out.report.vsplits += attached;
  ++out.answers;
  out.report.latency_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - answer.sent_at).count();
  if (options_.on_attached) options_.on_attached();
  return attached;
}

// The leaves held that `view` would want split: reached from the roots through nodes qrefine wants split
// (criteria.h, the same function adapt() evaluates), in walk order. Leaves of the model never qualify
// (qrefine is strict), so each names a split the server has. A forced chain's leaf is not predicted.
std::vector<uint32_t> ReceiverClient::leaves_wanted(const ViewParams& view) {
  const ViewCriteria criteria = make_criteria(view, options_.tolerance);
  const VertexHierarchy& hierarchy = session_.hierarchy();
  const float scale = session_.base().scale;
  std::vector<uint32_t> stack, leaves;
  for (uint32_t tree = hierarchy.root_count(); tree-- > 0;) stack.push_back(hierarchy.root_slot(tree));
  while (!stack.empty()) {
    const uint32_t slot = stack.back();
    stack.pop_back();
    if (!qrefine(criteria, hierarchy.position(slot), dequantize_refine(hierarchy.refine(slot), scale))) continue;
    if (hierarchy.is_leaf(slot)) {
      leaves.push_back(slot);
      continue;
    }
    stack.push_back(hierarchy.first_child(slot) + 1);
    stack.push_back(hierarchy.first_child(slot));
  }
  return leaves;
}

// Prefetch along the predicted path: what the next camera (extrapolated from the last two) would want and
// the client neither holds nor has asked for, in rank order as that camera would see the mesh. Sent while
// the view's wants are all on the wire and the pipe has room; their splits are attached as held data like
// any answer's, and adapt() makes them only when a view wants them.
std::deque<ReceiverClient::Request> ReceiverClient::plan_prefetch() {
  if (cameras_.size() < 2) return {};
  const std::optional<Camera> next = extrapolate(cameras_[0], cameras_[1]);
  if (!next) return {};
  const ViewParams view = session_.view_params(*next);
  std::vector<Wanted> ids = ranked(leaves_wanted(view), view);
  const std::vector<VertexId> on_wire = keys_on_wire();
  std::erase_if(ids, [&](const Wanted& w) {
    return std::binary_search(on_wire.begin(), on_wire.end(), key(w.id), protocol::code_order);
  });
  std::vector<Request> requests = requests_for(ids);
  return {std::make_move_iterator(requests.begin()), std::make_move_iterator(requests.end())};
}

// The idle fetch's next batch: held leaves whose splits some view may ask for (never_refines() is false:
// the others come only when a split forces them), largest error (max of mu and delta) first, so the model
// fills in coarse to fine as a view-independent stream would. A batch is bounded, so planning costs one
// walk of the held leaves per batch sent, not per frame.
std::deque<ReceiverClient::Request> ReceiverClient::plan_background() {
  constexpr size_t kBatchIds = 4096;
  const VertexHierarchy& hierarchy = session_.hierarchy();
  const std::vector<VertexId> on_wire = keys_on_wire();
  std::vector<std::pair<uint16_t, uint32_t>> leaves;  // (error, slot)
  for (uint32_t slot = 0; slot < hierarchy.size(); ++slot) {
    if (!hierarchy.is_leaf(slot) || never_refines(hierarchy.refine(slot))) continue;
    if (std::binary_search(on_wire.begin(), on_wire.end(), key(hierarchy.id(slot)), protocol::code_order)) continue;
    // Half-float bits of lengths >= 0 order as the lengths do.
    const RefineInfo& info = hierarchy.refine(slot);
    leaves.emplace_back(std::max(info.mu, info.delta), slot);
  }
  const size_t batch = std::min(leaves.size(), kBatchIds);
  std::partial_sort(leaves.begin(), leaves.begin() + ptrdiff_t(batch), leaves.end(), [](const auto& a, const auto& b) {
    return a.first > b.first || (a.first == b.first && a.second < b.second);
  });
  std::vector<Wanted> ids;
  ids.reserve(batch);
  for (size_t i = 0; i < batch; ++i) ids.push_back({hierarchy.id(leaves[i].second), options_.descendant_depth});
  std::vector<Request> requests = requests_for(ids);
  return {std::make_move_iterator(requests.begin()), std::make_move_iterator(requests.end())};
}

// Prefetched ids whose splits the mesh has made (the front runs below them), counted once and forgotten.
uint32_t ReceiverClient::count_prefetch_used() {
  const VertexHierarchy& hierarchy = session_.hierarchy();
  const SelectiveMesh& mesh = session_.mesh();
  const auto used = [&](VertexId id) {
    const uint32_t slot = hierarchy.find(id);
    if (slot == kNone || hierarchy.is_leaf(slot)) return false;  // not in yet
    for (uint32_t s = slot; s != kNone; s = hierarchy.parent(s))
      if (mesh.is_active(s)) return false;
    return true;
  };
  const size_t before = prefetched_.size();
  std::erase_if(prefetched_, used);
  const auto count = uint32_t(before - prefetched_.size());
  totals_.prefetch_used += count;
  return count;
}

ReceiverFrame ReceiverClient::frame(const Camera& camera) {
  return options_.free_running ? run_free(camera, false) : run(camera, false);
}

ReceiverFrame ReceiverClient::begin(const Camera& camera) {
  if (!session_.has_model()) fail("stream", "no model open");
  ReceiverFrame out;
  out.report.frame = ++frame_;
  if (cameras_.size() == 2) cameras_.erase(cameras_.begin());
  cameras_.push_back(camera);
  prefetch_queue_.clear();  // ranked for the last frame's extrapolation
  prefetch_planned_ = false;
  session_.refinement().set_view(session_.view_params(camera));
  return out;
}

void ReceiverClient::finish(ReceiverFrame& out, const HttpCounters& before, const ReceiverTotals& totals_before) {
  if (session_.has_model()) {  // else a 410 dropped the mesh: the next version is opening
    out.prefetch_used = count_prefetch_used();
    out.report.faces = session_.mesh().face_count();
  }
  const HttpCounters& after = http_->counters();
  out.report.up_bytes = after.bytes_up - before.bytes_up;
  out.report.down_bytes = after.bytes_down - before.bytes_down;
  out.payload_down = after.payload_down - before.payload_down;
  out.split_requests = uint32_t(totals_.split_requests - totals_before.split_requests);
  out.cache_hits = uint32_t(totals_.cache_hits - totals_before.cache_hits);
  out.cancelled = uint32_t(totals_.cancelled - totals_before.cancelled);
  out.stale_arrivals = uint32_t(totals_.stale_arrivals - totals_before.stale_arrivals);
  out.prefetched = uint32_t(totals_.prefetched - totals_before.prefetched);
  out.rankings = uint32_t(totals_.rankings - totals_before.rankings);
  out.background = uint32_t(totals_.background_ids - totals_before.background_ids);
  out.queued = uint32_t(queued_ids());
  out.in_flight = uint32_t(wire_.size());
}

// Rounds of adapt -> rank -> GET -> attach until the view wants nothing more or the budget is spent;
// prefetch only in a path's frames, not while settling. A round ends when the answers to what it asked for are in; a
// frame's first round re-ranks what the last frame left queued.
ReceiverFrame ReceiverClient::run(const Camera& camera, bool settling) {
  const HttpCounters before = http_->counters();
  const ReceiverTotals totals_before = totals_;
  const auto start = std::chrono::steady_clock::now();
  ReceiverFrame out = begin(camera);
  const bool may_prefetch = options_.prefetch && !settling;  // nothing follows the settling
  bool wants = rerank(camera);
  out.rounds = wants;
  uint32_t answers = 0;
  size_t attached = 0;  // since the last ranking
  // The answers are ranked with the rest of the front as they come, not once a round's are all in: the
  // children of a large error compete with what is still queued, so the largest errors go first at every
  // level, as in the PM order. A ranking renders the mesh and walks the front, so it waits until the
  // splits attached since the last are a sixteenth of the ids queued and a list's worth (ids_per_request:
  // blocks' small answers add up first), or the queue is empty, or the refresh period is over.
  while (wants) {
    fill_pipe(may_prefetch, false);
    if (answers > 0 && over_budget(answers, start)) break;
    if (wire_.empty()) break;
    ++answers;
    const size_t got = receive_one(out);
    if (got == 0) break;  // a valid server answers every id with its split: one that has no more ends it
    attached += got;
    const size_t queued = queued_ids();
    if (queued > 0 && (attached * kRerankShare < queued || attached < options_.ids_per_request) && !ranking_due())
      continue;
    attached = 0;
    wants = rerank(camera);
    out.rounds += wants;
  }

  if (opening_) {  // a 410: this frame again on the version it names
    await_open();
    return run(camera, settling);
  }
  if (may_prefetch && !wants) fill_pipe(true, false);
  out.satisfied = !wants;
  out.report.requested = out.rounds > 0;
  if (out.report.requested)
    out.report.latency_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  finish(out, before, totals_before);
  return out;
}

// One frame that never waits: what the connection can do at once is done, every answer fully arrived is
// attached, the view is adapted to and, when a ranking is due (moved camera, refresh period, new options,
// an empty queue while the adaptation wants a split not asked for), ranked anew (queued ids it no longer wants are dropped unsent); the pipe gets
// what fits and, with room left, the predicted view's splits, then with the view satisfied the idle
// fetch's. The latency reported is the last answer attached's, from its GET written.
ReceiverFrame ReceiverClient::run_free(const Camera& camera, bool settling) {
  const HttpCounters before = http_->counters();
  const ReceiverTotals totals_before = totals_;
  ReceiverFrame out = begin(camera);
  http_->poll();
  attach_arrived(out);
  if (opening_) {  // a 410: the version it names opens over the next frames (poll_open)
    poll_open();
    out.satisfied = false;
    finish(out, before, totals_before);
    return out;
  }
  adapt_for_view(session_.refinement());
  const bool moved = !ranked_camera_ || !same_camera(*ranked_camera_, camera);
  // The area ranking's wants are its ranking's (missing() lists every leaf with a split): it ranks each frame.
  const bool ranked = moved || options_.ranking == Ranking::area || options_.rerank_ms == 0 || ranking_due() ||
                      (queue_.empty() && wants_unasked());
  // Not ranked: the same camera, ranked lately, with its queue standing.
  const bool wants = ranked ? rank(camera) : !session_.refinement().missing().empty();
  out.rounds = ranked && wants;
  fill_pipe(options_.prefetch && !settling, options_.background_bytes > 0 && !settling && !wants);
  http_->poll();  // the GETs just handed over start on their way
  out.satisfied = !wants;
  out.report.requested = wants;
  finish(out, before, totals_before);
  return out;
}

void ReceiverClient::settle(const Camera& camera) {
  if (options_.free_running) settle_free(camera);
  else settle_locked(camera);
}

// Free-running frames at the held camera, waiting for an answer between them, until its view is
// satisfied (or an answer brings nothing: a server with no more); then what is still on the wire is read
// and the refinement converges, as in lock-step.
void ReceiverClient::settle_free(const Camera& camera) {
  settle_frames_ = 0;
  for (;;) {
    if (opening_) await_open();
    const ReceiverFrame r = run_free(camera, true);
    ++settle_frames_;
    if (opening_) continue;
    if (r.satisfied || wire_.empty() || (r.answers > 0 && r.report.vsplits == 0)) break;
    http_->wait();
  }
  ReceiverFrame rest;
  while (!wire_.empty()) {
    http_->wait();
    attach_arrived(rest);
  }
  if (opening_) return settle_free(camera);  // a 410 among the last answers
  session_.refinement().converge();
}

void ReceiverClient::settle_locked(const Camera& camera) {
  // Each frame reads an answer or sends nothing more: a frame that brought nothing and left nothing in
  // flight will not be followed by one that does.
  settle_frames_ = 0;
  for (;;) {
    const ReceiverFrame r = run(camera, true);
    ++settle_frames_;
    if (r.satisfied || (r.report.vsplits == 0 && r.in_flight == 0)) break;
  }
  ReceiverFrame rest;
  while (!wire_.empty()) receive_one(rest);  // prefetched or stale: read, as every GET sent is
  if (opening_) {  // a 410 among them
    await_open();
    return settle_locked(camera);
  }
  session_.refinement().converge();
}

}  // namespace pms::client
