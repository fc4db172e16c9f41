// The routes of the receiver-driven mode: GET /models, GET /models/M/V/base, POST /models/M/V/splits and its
// GET form /models/M/V/splits/CODE, and GET /models/M/V/blocks/TREE/NODE/DEPTH (docs/protocol.md,
// "Receiver-driven over HTTP"), each under the model's version, /models/M/VERSION/...; a multilevel model's go to
// multilevel_routes.h. Each URL has one answer for a given model file: strong ETags, immutable. GET /models,
// which names the versions, is the one answer revalidated.
#define XXH_INLINE_ALL
#include <xxhash.h>
#include <array>
#include <charconv>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <optional>

#include "protocol/base64url.h"
#include "protocol/message_types.h"
#include "protocol/split_request.h"
#include "protocol/url_segment.h"
#include "server/http_answers.h"
#include "server/http_routes.h"
#include "server/multilevel_routes.h"
#include "server/split_lookup.h"
#include "server/split_records_body.h"
#include "spm/vertex_id.h"

namespace pms::server {
namespace {

using protocol::ErrorCode;
using protocol::ProtocolError;

// At most kMaxSegments + 1 segments, so that a URL with too many ends in no route.
constexpr size_t kMaxSegments = 8;
struct Segments {
  std::array<std::string_view, kMaxSegments + 1> at;
  size_t count = 0;
  std::span<const std::string_view> all() const { return {at.data(), count}; }
};

Segments segments_of(std::string_view path) {
  Segments segments;
  while (!path.empty() && segments.count <= kMaxSegments) {
    path.remove_prefix(1);  // the '/'
    const size_t end = std::min(path.find('/'), path.size());
    segments.at[segments.count++] = path.substr(0, end);
    path.remove_prefix(end);
  }
  return segments;
}

// A strong ETag from what the bytes depend on: the model file's content, the wire's quantization, the
// record format and the canonical URL of the resource, "/models/NAME" then `resource`'s pieces, hashed as
// they are, without building the URL; the URL's version is left out, as the three before it make it.
std::string etag_of(const ServedModel& model, std::initializer_list<std::string_view> resource) {
  XXH64_state_t state;
  XXH64_reset(&state, 0);
  const uint64_t content = model.file->content_checksum();
  const uint32_t format[2] = {model.context.grid.bits, model.records_format};
  XXH64_update(&state, &content, sizeof content);
  XXH64_update(&state, format, sizeof format);
  for (std::string_view piece : {std::string_view("/models/"), std::string_view(model.name)})
    XXH64_update(&state, piece.data(), piece.size());
  for (std::string_view piece : resource) XXH64_update(&state, piece.data(), piece.size());
  return etag_text(XXH64_digest(&state));
}

// If-None-Match uses the weak comparison (RFC 9110 §13.1.2): W/ prefixes are ignored.
bool matches(std::string_view if_none_match, std::string_view etag) {
  while (!if_none_match.empty()) {
    const size_t comma = std::min(if_none_match.find(','), if_none_match.size());
    std::string_view tag = if_none_match.substr(0, comma);
    while (!tag.empty() && (tag.front() == ' ' || tag.front() == '\t')) tag.remove_prefix(1);
    while (!tag.empty() && (tag.back() == ' ' || tag.back() == '\t')) tag.remove_suffix(1);
    if (tag.starts_with("W/")) tag.remove_prefix(2);
    if (tag == "*" || tag == etag) return true;
    if_none_match.remove_prefix(std::min(comma + 1, if_none_match.size()));
  }
  return false;
}

int status_of(ErrorCode code) {
  switch (code) {
    case ErrorCode::bad_id:
      return 404;
    case ErrorCode::too_large:
      return 413;
    default:
      return 400;
  }
}

nlohmann::json progressive_entry(const ServedModel& model) {
  const protocol::ModelInfo& info = model.info;
  return {{"name", info.name},
          {"kind", "progressive"},
          {"version", model.version},
          {"faces", info.input_faces},
          {"base_vertices", info.base_vertices},
          {"vsplits", info.vsplits},
          {"tree_id_bits", info.tree_id_bits},
          {"node_id_bits", info.node_id_bits},
          {"position_bits", model.context.grid.bits},
          {"records_format", model.records_format},
          {"record_forms", {"info", "plain"}},
          {"block_depth", kSuggestedBlockDepth}};
}

// The one answer whose bytes change with the model set: a cache may use it for max-age, then asks again
// with If-None-Match, and a 304 costs the origin a hash of the list.
HttpAnswer catalogue_answer(const Catalogue& catalogue, const HttpLimits& limits, const HttpRequest& request) {
  nlohmann::json models = nlohmann::json::array();
  for (const auto& model : catalogue.models()) models.push_back(progressive_entry(*model));
  for (const auto& model : catalogue.multilevel_models()) models.push_back(multilevel_entry(*model));
  const std::string text = nlohmann::json{{"models", models}}.dump() + "\n";
  HttpAnswer answer = fresh(request, etag_text(XXH64(text.data(), text.size(), 0)), "application/json");
  answer.caching = Caching::max_age;
  answer.max_age_s = limits.catalogue_max_age_s;
  if (answer.status == 200) answer.owned.assign(text.begin(), text.end());
  return answer;
}

// A URL of another version of a model than the one served (docs/protocol.md, "Versions"): 410 Gone, not
// 404, so a client tells "re-open on the version this names" from "no such model"; its body is the
// model's catalogue entry as GET /models has it now, from the origin (no cache stores a 410 marked
// no-store), so a client behind a cache whose GET /models is not yet stale learns the new version at once.
HttpAnswer replaced_answer(const std::string& name, std::string_view asked, const nlohmann::json& entry) {
  const std::string version = entry.value("version", "");
  const std::string text = nlohmann::json{{"error", "model '" + name + "' is version " + version + " here, not " +
                                                        std::string(asked) + ": open that version"},
                                          {"model", entry}}
                               .dump() +
                           "\n";
  HttpAnswer answer = error_answer(410, "");
  answer.content_type = "application/json";
  answer.owned.assign(text.begin(), text.end());
  return answer;
}

HttpAnswer base_answer(const ServedModel& model, const HttpRequest& request) {
  const PhaseTimer timer(request.phases, Phase::send_base);
  HttpAnswer answer = fresh(request, etag_of(model, {"/base"}), "application/octet-stream");
  if (answer.status == 200) {
    answer.shared = model.base_frame;
    answer.shared_offset = protocol::kFrameHeaderBytes;
  }
  return answer;
}

// The records of a decoded request; `etag` is its canonical URL's (the GET form's, also for a POST).
HttpAnswer splits_answer(const ServedModel& model, const HttpLimits& limits, const HttpRequest& request,
                         RecordForm form, const protocol::SplitRequest& split_request, const std::string& etag) {
  std::vector<uint32_t> nodes;
  {
    const PhaseTimer timer(request.phases, Phase::search_splits);
    nodes = requested_nodes(model.model(), split_request, limits.max_response_splits);
  }
  HttpAnswer answer = fresh(request, etag, "application/octet-stream");
  answer.split_resource = true;
  if (answer.status == 200) {
    answer.builder = std::make_shared<SplitRecordsWriter>(model, split_request, nodes, form, request.phases);
    answer.splits = nodes.size();
  }
  return answer;
}

// The path piece before a records resource: none for the info form, /plain for the plain one.
std::string_view form_path(RecordForm form) { return form == RecordForm::plain ? "/plain" : ""; }
// The code tables every record of the model in `form` is coded with.
HttpAnswer codec_answer(const ServedModel& model, const HttpRequest& request, RecordForm form) {
  const PhaseTimer timer(request.phases, Phase::send_base);
  HttpAnswer answer = fresh(request, etag_of(model, {form_path(form), "/codec"}), "application/octet-stream");
  if (answer.status == 200) answer.shared = model.tables->records(form).codec_tables;
  return answer;
}

protocol::SplitRequest decode_code(const ServedModel& model, const HttpLimits& limits, const HttpRequest& request,
                                   std::span<const uint8_t> code) {
  const PhaseTimer timer(request.phases, Phase::decode_ids);
  protocol::SplitRequestLimits bounds;
  bounds.root_count = model.model().root_count;
  bounds.max_node_depth = int(model.context.node_id_bits) - 1;  // the deepest level holds leaves only
  bounds.max_ids = limits.max_request_ids;
  bounds.max_depth = limits.max_request_depth;
  bounds.max_bytes = limits.max_body_bytes;
  return protocol::decode_split_request(code, bounds);
}

HttpAnswer block_answer(const ServedModel& model, const HttpLimits& limits, const HttpRequest& request, RecordForm form,
                        std::span<const std::string_view> at) {
  uint64_t tree = 0, node = 0, depth = 0;
  if (!parse_decimal(at[0], tree) || !parse_decimal(at[1], node) || !parse_decimal(at[2], depth) || node == 0)
    return error_answer(400, "a block is /models/M/blocks/TREE/NODE/DEPTH in plain decimal, NODE >= 1");
  if (depth > limits.max_request_depth)
    return error_answer(400, "block depth " + std::to_string(depth) + " is over the limit of " +
                                 std::to_string(limits.max_request_depth));
  const VertexId id{uint32_t(tree), node};
  if (tree >= model.model().root_count || uint64_t(id.depth()) >= model.context.node_id_bits)
    return error_answer(404, to_string(id) + " is not a split of model '" + model.name + "'");
  // One URL per set of records: blocks tile each tree in bands of depth + 1 levels.
  if (id.depth() % (depth + 1) != 0)
    return error_answer(400, "a block of depth " + std::to_string(depth) +
                                 " starts at a node whose depth is a "
                                 "multiple of " +
                                 std::to_string(depth + 1) + "; " + to_string(id) + " is at depth " +
                                 std::to_string(id.depth()));
  return splits_answer(model, limits, request, form, {uint32_t(depth), {id}},
                       etag_of(model, {form_path(form), "/blocks/", at[0], "/", at[1], "/", at[2]}));
}

// Nothing when `mode`'s tables of the model are built; a 503 to wait on while they are being built (the
// transport waits, the client sees it only past the request deadline), a 500 when their build failed.
std::optional<HttpAnswer> tables_pending(const ServedModel& model, ServedMode mode) {
  const ModelTables::State state = model.tables->state(mode);
  if (state == ModelTables::State::ready) return std::nullopt;
  const std::string tables = "model '" + model.name + "': its " + served_mode_name(mode) + " tables ";
  if (state == ModelTables::State::failed)
    return error_answer(500, tables + "could not be built: " + model.tables->failure(mode));
  HttpAnswer answer = error_answer(503, tables + "are being built; try again");
  answer.waits_for = &model;
  answer.waits_for_mode = mode;
  return answer;
}

// A .pms model's multilevel resources are those of a .pml model (multilevel_routes.h), its levels derived.
bool multilevel_resource(std::span<const std::string_view> s) {
  return s[2] == "head" || s[2] == "levels" || s[2] == "compressed" || s[2] == "multilevel";
}

// The records resources of `form`, s[at...]: codec, splits (POST), splits/CODE, blocks/TREE/NODE/DEPTH.
HttpAnswer records_route(const ServedModel& model, const HttpLimits& limits, const HttpRequest& request,
                         RecordForm form, std::span<const std::string_view> s, size_t at) {
  const std::span<const std::string_view> r = s.subspan(at);
  const bool get = request.method == "GET" || request.method == "HEAD";
  const bool post_route = r.size() == 1 && r[0] == "splits";
  const bool get_route =
      (r.size() == 1 && r[0] == "codec") || (r.size() == 2 && r[0] == "splits") || (r.size() == 4 && r[0] == "blocks");
  if (!post_route && !get_route) return error_answer(404, "no such resource (docs/protocol.md lists them)");
  if (post_route && request.method != "POST") return method_not_allowed("POST");
  if (get_route && !get) return method_not_allowed("GET, HEAD");
  if (auto pending = tables_pending(model, ServedMode::receiver)) return std::move(*pending);
  if (r[0] == "codec") return codec_answer(model, request, form);
  if (r[0] == "blocks") return block_answer(model, limits, request, form, r.subspan(1));
  if (post_route)
    return splits_answer(model, limits, request, form, decode_code(model, limits, request, request.body),
                         etag_of(model, {form_path(form), "/splits/", protocol::base64url_encode(request.body)}));
  if (r[1].size() > (uint64_t(limits.max_body_bytes) * 4 + 2) / 3)
    return error_answer(414, "a request code of over " + std::to_string(limits.max_body_bytes) + " bytes");
  const auto code = [&] {
    const PhaseTimer timer(request.phases, Phase::decode_ids);
    return protocol::base64url_decode(r[1]);
  }();
  if (!code) return error_answer(400, "the request code is not canonical base64url (RFC 4648 §5, no padding)");
  // Strict base64url has one text per code: the segment is the canonical URL's.
  return splits_answer(model, limits, request, form, decode_code(model, limits, request, *code),
                       etag_of(model, {form_path(form), "/splits/", r[1]}));
}
// A .pms model's resources under /models/{m}/{version}/: `s` is the URL's segments without the version.
HttpAnswer progressive_route(const ServedModel& model, const HttpLimits& limits, const HttpRequest& request,
                             std::span<const std::string_view> s) {
  if (multilevel_resource(s)) {
    if (auto pending = tables_pending(model, ServedMode::multilevel)) return std::move(*pending);
    return multilevel_route(model.tables->multilevel(), request, s);
  }
  if (s.size() >= 4 && s[2] == "plain") return records_route(model, limits, request, RecordForm::plain, s, 3);
  if (s.size() == 3 && s[2] == "base") {
    if (request.method != "GET" && request.method != "HEAD") return method_not_allowed("GET, HEAD");
    return base_answer(model, request);
  }
  return records_route(model, limits, request, RecordForm::info, s, 2);
}

// /models/{m}/{version}/...: the model, then its version (410 for another), then the resource.
HttpAnswer model_route(const Catalogue& catalogue, const HttpLimits& limits, const HttpRequest& request,
                       std::span<const std::string_view> segments) {
  const std::optional<std::string> name = protocol::url_segment_decode(segments[1]);
  if (!name) return error_answer(400, "the model name in the URL is not a path segment (RFC 3986: escape it as %XX)");
  const ServedMultilevel* multilevel = catalogue.find_multilevel(*name);
  const ServedModel* progressive = catalogue.find(*name);
  if (!multilevel && !progressive) return error_answer(404, "no model named '" + *name + "'");
  const std::string_view version = segments[2];
  if (segments.size() < 4 || !protocol::is_model_version(version))
    return error_answer(404, "a model's resources are /models/NAME/VERSION/..., VERSION as GET /models names it");
  const std::string& served = multilevel ? multilevel->version : progressive->version;
  if (version != served)
    return replaced_answer(*name, version, multilevel ? multilevel_entry(*multilevel) : progressive_entry(*progressive));
  // The routes below read the segments as /models/{m}/RESOURCE...
  std::array<std::string_view, kMaxSegments> s;
  s[0] = segments[0];
  s[1] = segments[1];
  std::copy(segments.begin() + 3, segments.end(), s.begin() + 2);
  const std::span<const std::string_view> rest(s.data(), segments.size() - 1);
  if (multilevel) return multilevel_route(*multilevel, request, rest);
  return progressive_route(*progressive, limits, request, rest);
}

// The one spelling of `target` (RFC 3986 §6.2.2's normal form, and a model's name escaped as the clients
// escape it: every byte outside the unreserved set, so "a!b" and "a%21b", which the routes take for one
// name, are one URL); nothing when `target` is no path a client could be sent to.
std::optional<std::string> canonical_target(std::string_view target) {
  std::optional<std::string> path = protocol::url_path_normalize(target);
  if (!path) return std::nullopt;
  const Segments s = segments_of(*path);
  if (s.count < 2 || s.at[0] != "models") return path;
  if (const std::optional<std::string> name = protocol::url_segment_decode(s.at[1]))
    path->replace(size_t(s.at[1].data() - path->data()), s.at[1].size(), protocol::url_segment_encode(*name));
  return path;
}

// A URL spelled another way than its resource's canonical URL is sent there, not served: a second URL with
// the same bytes would be a second cache entry, and a way around a cache's copy (a miss at the origin for
// as many spellings as a client cares to write). The redirect is always correct, as both spellings name the
// same resource (or the same absence of one); a 404 would break a hand-typed URL for nothing. 308 keeps a
// POST a POST (RFC 9110 §15.4.9); no-store, as every answer but a 200 or 304: a cache that stored the
// redirects would hold an entry per spelling, which is what the redirect is there to prevent.
std::optional<HttpAnswer> redirect_to_canonical(const HttpLimits& limits, const HttpRequest& request) {
  std::optional<std::string> canonical = canonical_target(request.target);
  if (!canonical || *canonical == request.target) return std::nullopt;
  if (canonical->size() > limits.max_target_bytes)  // escaping lengthened it: no GET could reach it
    return error_answer(414, "the URL's canonical form is over " + std::to_string(limits.max_target_bytes) + " bytes");
  const bool get = request.method == "GET" || request.method == "HEAD";
  HttpAnswer answer = error_answer(get ? 301 : 308, "the URL of this resource is " + *canonical);
  answer.location = std::move(*canonical);
  return answer;
}

}  // namespace

bool parse_decimal(std::string_view text, uint64_t& value) {
  if (text.empty() || (text.size() > 1 && text[0] == '0')) return false;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  return ec == std::errc() && end == text.data() + text.size();
}

std::string etag_text(uint64_t hash) {
  uint8_t bytes[8];
  for (int i = 0; i < 8; ++i) bytes[i] = uint8_t(hash >> (56 - 8 * i));
  return '"' + protocol::base64url_encode(bytes) + '"';
}

HttpAnswer fresh(const HttpRequest& request, const std::string& etag, const char* content_type) {
  HttpAnswer answer;
  answer.status = matches(request.if_none_match, etag) ? 304 : 200;
  answer.content_type = content_type;
  answer.etag = etag;
  answer.caching = Caching::immutable;
  return answer;
}

HttpAnswer method_not_allowed(const char* allow) {
  HttpAnswer answer = error_answer(405, std::string("this resource takes ") + allow);
  answer.allow = allow;
  return answer;
}

void finish_body(HttpAnswer& answer) {
  if (!answer.builder) return;
  answer.builder->build(std::chrono::steady_clock::time_point::max());
  answer.owned = answer.builder->take();
  answer.builder.reset();
}

HttpAnswer error_answer(int status, const std::string& text) {
  HttpAnswer answer;
  answer.status = status;
  answer.owned.assign(text.begin(), text.end());
  answer.owned.push_back('\n');
  return answer;
}

HttpAnswer route(const Catalogue& catalogue, const HttpLimits& limits, const HttpRequest& request) {
  if (request.target.size() > limits.max_target_bytes)
    return error_answer(414,
                        "the URL is over " + std::to_string(limits.max_target_bytes) + " bytes; POST large requests");
  if (request.target.empty() || request.target[0] != '/' || request.target.find('?') != std::string_view::npos)
    return error_answer(400, "the URL must be a path without a query string");
  if (std::optional<HttpAnswer> redirect = redirect_to_canonical(limits, request)) return std::move(*redirect);
  const Segments segments = segments_of(request.target);
  const std::span<const std::string_view> s = segments.all();
  try {
    if (s.size() == 1 && s[0] == "models") {
      if (request.method != "GET" && request.method != "HEAD") return method_not_allowed("GET, HEAD");
      return catalogue_answer(catalogue, limits, request);
    }
    if (s.size() >= 3 && s[0] == "models") return model_route(catalogue, limits, request, s);
  } catch (const ProtocolError& e) {
    return error_answer(status_of(e.code), e.what());
  }
  return error_answer(404, "no such resource (docs/protocol.md lists them)");
}

}  // namespace pms::server
