// The multilevel client (multilevel_client.h): levels fetched coarsest first, pipelined, each added on
// arrival; a LOD rule per frame over what the catalogue says of each level.
#include "client/multilevel_client.h"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "common/error.h"
#include "protocol/url_segment.h"

namespace pms::client {
namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

[[noreturn]] void refused(const std::string& target, const HttpAnswer& answer) {
  std::string text(answer.body.begin(), answer.body.begin() + std::min<size_t>(answer.body.size(), 200));
  while (!text.empty() && (text.back() == '\n' || text.back() == '\r')) text.pop_back();
  fail("GET " + target, "HTTP " + std::to_string(answer.status) + ": " + text);
}

nlohmann::json catalogue_models(HttpConnection& http) {
  const std::string target = "/models";
  const HttpAnswer answer = http.get(target);
  if (answer.status != 200) refused(target, answer);
  nlohmann::json json = nlohmann::json::parse(answer.body.begin(), answer.body.end(), nullptr, false);
  if (json.is_discarded() || !json.is_object() || !json.contains("models") || !json["models"].is_array())
    fail("GET " + target, "not the catalogue's JSON");
  return std::move(json["models"]);
}

bool is_kind(const nlohmann::json& entry, const char* kind) {
  return entry.is_object() && entry.value("kind", "") == kind && entry.contains("name") && entry["name"].is_string();
}

bool is_multilevel(const nlohmann::json& entry) { return is_kind(entry, "multilevel"); }

// A progressive (.pms) model's levels are derived by the server when first asked for: its multilevel entry
// is a resource of its own, answered once they are.
nlohmann::json derived_entry(HttpConnection& http, const std::string& model) {
  const std::string target = protocol::model_path(model) + "/multilevel";
  const HttpAnswer answer = http.get(target);
  if (answer.status != 200) refused(target, answer);
  nlohmann::json entry = nlohmann::json::parse(answer.body.begin(), answer.body.end(), nullptr, false);
  if (!is_multilevel(entry) || entry["name"].get<std::string>() != model)
    fail("GET " + target, "not the multilevel entry of model '" + model + "'");
  return entry;
}

// `count` finite numbers, coarsest first in the catalogue, returned per level (0 finest).
template <typename T>
std::vector<T> per_level(const nlohmann::json& entry, const char* key, uint32_t count) {
  const auto it = entry.find(key);
  if (it == entry.end() || !it->is_array() || it->size() != count)
    fail("GET /models",
         std::string("the multilevel entry's '") + key + "' is not " + std::to_string(count) + " numbers");
  std::vector<T> out(count);
  for (uint32_t i = 0; i < count; ++i) {
    const nlohmann::json& x = (*it)[i];
    if (!x.is_number() || !std::isfinite(x.get<double>()) || x.get<double>() < 0)
      fail("GET /models", std::string("the multilevel entry's '") + key + "' holds a value that is not a number >= 0");
    out[count - 1 - i] = x.get<T>();
  }
  return out;
}

// /models/{m}/ or /models/{m}/compressed/, where the model's head and levels are.
std::string model_prefix(const std::string& model, bool compressed) {
  return protocol::model_path(model) + (compressed ? "/compressed/" : "/");
}

std::string level_target(const std::string& prefix, uint32_t level) {
  std::string target = prefix;
  target += "levels/";
  target += std::to_string(level);
  return target;
}

}  // namespace

MultilevelClient::MultilevelClient(const HttpUrl& server, const MultilevelOptions& options)
    : options_(options), http_(server, options.http) {}

std::vector<std::string> MultilevelClient::list() {
  std::vector<std::string> names;
  for (const nlohmann::json& entry : catalogue_models(http_))
    if (is_multilevel(entry)) names.push_back(entry["name"].get<std::string>());
  return names;
}

void MultilevelClient::read_entry(const std::string& model) {
  for (nlohmann::json entry : catalogue_models(http_)) {
    const bool progressive = is_kind(entry, "progressive");
    if ((!is_multilevel(entry) && !progressive) || entry["name"].get<std::string>() != model) continue;
    if (progressive) entry = derived_entry(http_, model);
    const uint32_t levels = entry.value("levels", 0u);
    if (levels == 0 || levels > options_.limits.max_levels)
      fail("GET /models", "model '" + model + "' has " + std::to_string(levels) + " levels");
    lod_triangles_ = per_level<uint32_t>(entry, "lod_triangles", levels);
    level_errors_ = per_level<float>(entry, "level_errors", levels);
    const auto center = entry.find("center");
    const auto radius = entry.find("radius");
    const auto finite = [](const nlohmann::json& x) { return x.is_number() && std::isfinite(x.get<double>()); };
    if (center == entry.end() || !center->is_array() || center->size() != 3 ||
        !std::all_of(center->begin(), center->end(), finite) || radius == entry.end() || !finite(*radius) ||
        radius->get<double>() < 0)
      fail("GET /models", "model '" + model + "' has no valid bounding sphere");
    for (int k = 0; k < 3; ++k) center_[k] = (*center)[k].get<float>();
    radius_ = radius->get<float>();
    return;
  }
  fail("GET /models", "no model named '" + model + "'");
}

void MultilevelClient::open(const std::string& model) {
  if (loader_) fail("open", "this client already holds '" + model_ + "'");
  opened_ = Clock::now();
  read_entry(model);
  const std::string target = model_prefix(model, options_.compressed) + "head";
  const HttpAnswer head = http_.get(target);
  if (head.status != 200) refused(target, head);
  loader_.emplace("GET " + target, head.body, options_.limits,
                  options_.compressed ? MultilevelForm::compressed : MultilevelForm::plain);
  if (loader_->level_count() != lod_triangles_.size()) fail("GET " + target, "its level count is not the catalogue's");
  lod_.emplace(loader_->mesh());
  model_ = model;
}

// A LOD l shows what is within error e_l; seen from a distance z, e_l covers e_l / (z * pixel_angle)
// pixels (Hoppe 1997 §4.3's kappa). z is the distance to the nearest point of the bounding sphere, so the
// rule holds for every vertex.
uint32_t MultilevelClient::wanted_level(const Camera& camera) const {
  const uint32_t top = uint32_t(lod_triangles_.size()) - 1;
  if (options_.budget > 0) {
    for (uint32_t l = 0; l < top; ++l)
      if (lod_triangles_[l] <= options_.budget) return l;
    return top;
  }
  const ViewParams view = view_params(camera);
  float sq = 0;
  for (int k = 0; k < 3; ++k) sq += (camera.eye[k] - center_[k]) * (camera.eye[k] - center_[k]);
  const float z = std::max(std::sqrt(sq) - radius_, 1e-6f * std::max(radius_, 1e-6f));
  for (uint32_t l = top + 1; l-- > 0;)
    if (level_errors_[l] <= options_.tolerance * z * view.pixel_angle) return l;
  return 0;
}

ViewParams MultilevelClient::view_params(const Camera& camera) const {
  float lo[3], hi[3];
  for (int k = 0; k < 3; ++k) {
    lo[k] = center_[k] - radius_;
    hi[k] = center_[k] + radius_;
  }
  return make_view(camera, lo, hi);
}

// GETs the levels still missing down to `level`, pipelined, and adds each as it arrives. Returns how many.
uint32_t MultilevelClient::load_to(uint32_t level) {
  if (loader_->complete() || loader_->finest_loaded() <= level) return 0;
  std::vector<std::string> targets;
  const std::string prefix = model_prefix(model_, options_.compressed);
  for (uint32_t l = loader_->finest_loaded(); l-- > level;) targets.push_back(level_target(prefix, l));
  uint32_t added = 0;
  http_.get_all(targets, [&](size_t index, HttpAnswer&& answer) {
    if (answer.status != 200) refused(targets[index], answer);
    const uint32_t l = loader_->next_level();
    loader_->add_level("GET " + targets[index], answer.body);
    const HttpCounters& c = http_.counters();
    arrivals_.push_back({l, answer.body.size(), c.bytes_down, c.payload_down, ms_since(opened_)});
    ++added;
  });
  lod_.emplace(loader_->mesh());  // the structure grew: nothing cached of it is kept
  return added;
}

void MultilevelClient::show(float level, MultilevelFrame& out) {
  const auto start = Clock::now();
  if (level == std::floor(level)) lod_->set_level(uint32_t(level));
  else lod_->set_level(level);
  out.lod_ms = ms_since(start);
  shown_ = level;
}

MultilevelFrame MultilevelClient::frame(const Camera& camera) {
  if (!loader_) fail("stream", "no model open");
  MultilevelFrame out;
  out.report.frame = ++frame_;
  const HttpCounters before = http_.counters();
  out.wanted_level = wanted_level(camera);
  const auto start = Clock::now();
  out.report.vsplits = load_to(out.wanted_level);
  if (out.report.vsplits > 0) {
    out.report.requested = true;
    out.report.latency_ms = ms_since(start);
  }
  const float target = float(std::max(out.wanted_level, loader_->finest_loaded()));
  float level = target;
  if (options_.morph_frames > 0 && shown_ >= 0) {
    const float step = 1.0f / float(options_.morph_frames);
    level = shown_ < target ? std::min(target, shown_ + step) : std::max(target, shown_ - step);
  }
  show(level, out);
  const HttpCounters& after = http_.counters();
  out.report.up_bytes = after.bytes_up - before.bytes_up;
  out.report.down_bytes = after.bytes_down - before.bytes_down;
  out.payload_down = after.payload_down - before.payload_down;
  out.report.faces = lod_->indices().size() / 3;
  out.level = lod_->level();
  out.levels_loaded = loader_->levels_loaded();
  return out;
}

void MultilevelClient::settle(const Camera& camera) {
  if (!loader_) fail("stream", "no model open");
  const uint32_t wanted = wanted_level(camera);
  load_to(wanted);
  MultilevelFrame ignored;
  show(float(std::max(wanted, loader_->finest_loaded())), ignored);
}

}  // namespace pms::client
