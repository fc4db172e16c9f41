// The receiver-driven client (receiver_client.h): the sender-driven client's frame loop, with the client
// choosing the splits itself — the leaves qrefine wants split, most screen area first — and fetching them
// by id with the cacheable GET form.
#include "client/receiver_client.h"

#include <algorithm>
#include <set>
#include <utility>
#include <nlohmann/json.hpp>

#include "common/bit_stream.h"
#include "common/error.h"
#include "protocol/base64url.h"
#include "protocol/server_messages.h"
#include "protocol/split_request.h"
#include "protocol/url_segment.h"
#include "refine/adapt.h"

namespace pms::client {
namespace {

std::string answer_text(const HttpAnswer& answer) {
  std::string text(answer.body.begin(), answer.body.begin() + std::min<size_t>(answer.body.size(), 200));
  while (!text.empty() && (text.back() == '\n' || text.back() == '\r')) text.pop_back();
  return text;
}

[[noreturn]] void refused(const std::string& target, const HttpAnswer& answer) {
  fail("GET " + target, "HTTP " + std::to_string(answer.status) + ": " + answer_text(answer));
}

// Frames without a cap reach the view's mesh for what is known in one adapt(); the extra passes only
// finish collapses that waited for a geomorph (as the sender-driven client does).
void adapt_for_view(SelectiveRefinement& refinement) {
  FrameStats stats = refinement.adapt();
  for (int pass = 0; pass < 64 && !stats.capped && stats.ops() > 0 && refinement.missing().empty(); ++pass)
    stats = refinement.adapt();
}

// Appended piece by piece: GCC 12 warns wrongly (-Wrestrict) on a chain of `+` with to_string().
std::string block_target(const std::string& model, VertexId root, uint32_t depth) {
  std::string target = protocol::model_path(model);
  target += "/blocks/";
  target += std::to_string(root.tree);
  target += '/';
  target += std::to_string(root.node);
  target += '/';
  target += std::to_string(depth);
  return target;
}

}  // namespace

const char* fetch_policy_name(FetchPolicy policy) { return policy == FetchPolicy::blocks ? "blocks" : "lists"; }

FetchPolicy fetch_policy_named(const std::string& name, const std::string& where) {
  if (name == "lists") return FetchPolicy::lists;
  if (name == "blocks") return FetchPolicy::blocks;
  fail(where, "'" + name + "' is not a fetch policy (lists or blocks)");
}

ReceiverClient::ReceiverClient(const HttpUrl& server, const ReceiverOptions& options)
    : options_(options), http_(server, options.http), importance_(RenderOptions{1}) {
  if (options.ids_per_request == 0) fail("receiver", "ids_per_request must be at least 1");
  if (options.block_depth > 8) fail("receiver", "block_depth must be at most 8 (the server's request depth limit)");
  session_.adapt_options.tolerance = options.tolerance;
  session_.adapt_options.morph_frames = options.morph_frames;
  session_.adapt_options.max_ops = options.max_ops;
  session_.refinement_info = true;  // the records carry the children's refinement info: the client refines
}

// GET /models: the array of models, checked to be one.
nlohmann::json ReceiverClient::catalogue() {
  const std::string target = "/models";
  const HttpAnswer answer = http_.get(target);
  if (answer.status != 200) refused(target, answer);
  nlohmann::json json = nlohmann::json::parse(answer.body.begin(), answer.body.end(), nullptr, false);
  if (json.is_discarded() || !json.is_object() || !json.contains("models") || !json["models"].is_array())
    fail("GET " + target, "not the catalogue's JSON");
  return std::move(json["models"]);
}

std::vector<std::string> ReceiverClient::list() {
  std::vector<std::string> names;
  for (const nlohmann::json& model : catalogue())
    if (model.is_object() && model.contains("name") && model["name"].is_string())
      names.push_back(model["name"].get<std::string>());
  return names;
}

void ReceiverClient::open(const std::string& model) {
  if (session_.has_model()) fail("open", "this client already holds '" + model_ + "'");
  const std::string target = protocol::model_path(model) + "/base";
  const HttpAnswer answer = http_.get(target);
  if (answer.status != 200) refused(target, answer);
  session_.on_base(protocol::decode_base(answer.body));
  model_ = model;
  for (const nlohmann::json& entry : catalogue())
    if (entry.is_object() && entry.value("name", "") == model) records_format_ = entry.value("records_format", 1u);
  if (records_format_ == 2) {
    const std::string tables = protocol::model_path(model) + "/codec";
    const HttpAnswer codec = http_.get(tables);
    if (codec.status != 200) refused(tables, codec);
    BitReader r(codec.body, "GET " + tables);
    codec_ = SplitCodec::deserialize(r);
    if (codec_.root_count() != session_.base().root_count() || codec_.position_bits() != session_.context().grid.bits)
      fail("GET " + tables, "code tables of another model or grid than its BASE");
  } else if (records_format_ != 1) {
    fail("GET /models", "records format " + std::to_string(records_format_) + " is not one this client reads");
  }
}

// The leaves the last adapt() could not split, the visible ones by the pixels of their faces, then the
// rest (forced chains' leaves can be out of sight) in the order adapt() found them.
std::vector<VertexId> ReceiverClient::ranked_missing(const Camera& camera) {
  SelectiveRefinement& refinement = session_.refinement();
  const std::span<const uint32_t> missing = refinement.missing();
  std::vector<uint32_t> sorted(missing.begin(), missing.end());
  std::sort(sorted.begin(), sorted.end());
  sorted.erase(std::unique(sorted.begin(), sorted.end()), sorted.end());
  const auto wanted = [&sorted](uint32_t slot) { return std::binary_search(sorted.begin(), sorted.end(), slot); };
  const std::vector<VertexArea>& ranked = importance_.rank(session_.mesh(), session_.view_params(camera), wanted);
  VertexHierarchy& hierarchy = session_.hierarchy();
  std::vector<uint8_t> taken(sorted.size(), 0);
  std::vector<VertexId> ids;
  ids.reserve(sorted.size());
  for (const VertexArea& area : ranked) {
    taken[size_t(std::lower_bound(sorted.begin(), sorted.end(), area.slot) - sorted.begin())] = 1;
    ids.push_back(hierarchy.id(area.slot));
  }
  for (const uint32_t slot : missing) {
    const size_t at = size_t(std::lower_bound(sorted.begin(), sorted.end(), slot) - sorted.begin());
    if (taken[at]) continue;
    taken[at] = 1;
    ids.push_back(hierarchy.id(slot));
  }
  return ids;
}

// ids_per_request ids to a URL, in rank order: each URL is the code of its id set.
ReceiverClient::Requests ReceiverClient::list_requests(const std::vector<VertexId>& ids) const {
  Requests out;
  for (size_t begin = 0; begin < ids.size(); begin += options_.ids_per_request) {
    const size_t end = std::min(ids.size(), begin + options_.ids_per_request);
    out.requests.push_back({0, std::vector<VertexId>(ids.begin() + begin, ids.begin() + end)});
    // The answer comes in code order, which format 2's bands are read in.
    std::sort(out.requests.back().ids.begin(), out.requests.back().ids.end(), protocol::code_order);
    const std::vector<uint8_t> code = protocol::encode_split_request(out.requests.back());
    out.targets.push_back(protocol::model_path(model_) + "/splits/" + protocol::base64url_encode(code));
  }
  return out;
}

// The block of each id (its ancestor at the top of its band of block_depth + 1 levels), in the rank order
// of the first id that needs it. An id the client lacks is a leaf of what it holds; the splits of its band
// above it would have come with its own block, so the id is that block's root, a vertex the client has,
// and no block is fetched twice (it would have brought the id): no record arrives twice. A block's answer is that of the request
// "its root, block_depth levels down", which is how format 2's bands are read.
ReceiverClient::Requests ReceiverClient::block_requests(const std::vector<VertexId>& ids) const {
  const int band = int(options_.block_depth) + 1;
  std::set<std::pair<uint32_t, uint64_t>> asked;
  Requests out;
  for (const VertexId id : ids) {
    const VertexId root = ancestor_at_depth(id, id.depth() / band * band);
    if (!asked.emplace(root.tree, root.node).second) continue;
    out.targets.push_back(block_target(model_, root, options_.block_depth));
    out.requests.push_back({options_.block_depth, {root}});
  }
  return out;
}

// GETs the splits of `ids` in their order (as the policy shapes the URLs) and attaches every answer as it
// arrives. Returns the splits attached.
size_t ReceiverClient::fetch(const std::vector<VertexId>& ids) {
  const Requests asked = options_.fetch == FetchPolicy::blocks ? block_requests(ids) : list_requests(ids);
  size_t attached = 0;
  http_.get_all(asked.targets, [&](size_t index, HttpAnswer&& answer) {
    if (answer.status != 200) refused(asked.targets[index], answer);
    cache_hits_ += answer.cache_status == "HIT";
    if (records_format_ == 2) {
      attached += session_.on_split_bands(answer.body, asked.requests[index], codec_);
    } else {
      const protocol::VSplits batch = protocol::decode_vsplits(answer.body, session_.context());
      session_.on_vsplits(batch);
      attached += batch.splits.size();
    }
    if (options_.on_attached) options_.on_attached();
  });
  split_requests_ += asked.targets.size();
  return attached;
}

ReceiverFrame ReceiverClient::frame(const Camera& camera) {
  if (!session_.has_model()) fail("stream", "no model open");
  ReceiverFrame out;
  out.report.frame = ++frame_;
  const HttpCounters before = http_.counters();
  const uint64_t requests_before = split_requests_, hits_before = cache_hits_;
  const auto start = std::chrono::steady_clock::now();
  SelectiveRefinement& refinement = session_.refinement();
  refinement.set_view(session_.view_params(camera));
  // Each round's answers let adapt() go one level deeper into the front; a model's depth bounds the rounds.
  for (uint32_t round = 0; round < 4096; ++round) {
    adapt_for_view(refinement);
    if (refinement.missing().empty()) break;
    ++out.rounds;
    out.report.requested = true;
    const size_t received = fetch(ranked_missing(camera));
    out.report.vsplits += received;
    if (received == 0) break;
  }
  if (out.report.requested)
    out.report.latency_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  const HttpCounters& after = http_.counters();
  out.report.up_bytes = after.bytes_up - before.bytes_up;
  out.report.down_bytes = after.bytes_down - before.bytes_down;
  out.payload_down = after.payload_down - before.payload_down;
  out.split_requests = uint32_t(split_requests_ - requests_before);
  out.cache_hits = uint32_t(cache_hits_ - hits_before);
  out.report.faces = session_.mesh().face_count();
  return out;
}

void ReceiverClient::settle(const Camera& camera) {
  frame(camera);
  session_.refinement().converge();
}

}  // namespace pms::client
