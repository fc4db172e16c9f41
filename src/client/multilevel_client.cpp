// The multilevel client (multilevel_client.h): levels fetched coarsest first, pipelined, each added on
// arrival; a LOD rule per frame over what the model's entry says of each level.
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


bool is_kind(const nlohmann::json& entry, const char* kind) {
  return entry.is_object() && entry.value("kind", "") == kind && entry.contains("name") && entry["name"].is_string();
}

bool is_multilevel(const nlohmann::json& entry) { return is_kind(entry, "multilevel"); }

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


std::string level_target(const std::string& prefix, uint32_t level) {
  std::string target = prefix;
  target += "levels/";
  target += std::to_string(level);
  return target;
}

// The coarsest level by a name that needs no level count (docs/protocol.md, "Multilevel over HTTP"), so
// it can go in the same round trip as the entry that says the count.
std::string coarsest_target(const std::string& prefix) { return prefix + "levels/coarsest"; }

}  // namespace

MultilevelClient::MultilevelClient(std::unique_ptr<HttpTransport> http, const MultilevelOptions& options)
    : options_(options), http_(std::move(http)) {
  if (!http_) fail("multilevel", "no transport");
}

std::vector<std::string> MultilevelClient::list() {
  std::vector<std::string> names;
  for (const nlohmann::json& entry : catalogue_models(http_->get("/models")))
    if (is_multilevel(entry)) names.push_back(entry["name"].get<std::string>());
  return names;
}

// GET /models/{m}/multilevel: the model's entry, the object GET /models lists for a .pml model and the one
// the server derives for a .pms model's levels (its GET /models entry says "progressive").
void MultilevelClient::read_entry(const std::string& model, const std::string& target, const HttpAnswer& answer) {
  if (answer.status != 200) refused(target, answer);
  const nlohmann::json entry = nlohmann::json::parse(answer.body.begin(), answer.body.end(), nullptr, false);
  if (!is_multilevel(entry) || entry["name"].get<std::string>() != model)
    fail("GET " + target, "not the multilevel entry of model '" + model + "'");
  const uint32_t levels = entry.value("levels", 0u);
  if (levels == 0 || levels > options_.limits.max_levels)
    fail("GET " + target, "model '" + model + "' has " + std::to_string(levels) + " levels");
  lod_triangles_ = per_level<uint32_t>(entry, "lod_triangles", levels);
  level_errors_ = per_level<float>(entry, "level_errors", levels);
  const auto center = entry.find("center");
  const auto radius = entry.find("radius");
  const auto finite = [](const nlohmann::json& x) { return x.is_number() && std::isfinite(x.get<double>()); };
  if (center == entry.end() || !center->is_array() || center->size() != 3 ||
      !std::all_of(center->begin(), center->end(), finite) || radius == entry.end() || !finite(*radius) ||
      radius->get<double>() < 0)
    fail("GET " + target, "model '" + model + "' has no valid bounding sphere");
  for (int k = 0; k < 3; ++k) center_[k] = (*center)[k].get<float>();
  radius_ = radius->get<float>();
}

// /models/{m}/{version}/ or /models/{m}/{version}/compressed/, where the model's head and levels are.
std::string MultilevelClient::prefix(bool compressed) const {
  return protocol::model_path(model_, version_) + (compressed ? "/compressed/" : "/");
}

// Its version from GET /models, then the version's entry and head (free-running: and the coarsest level)
// in one round trip.
void MultilevelClient::open(const std::string& model) {
  if (loader_ || opening_) fail("open", "this client already holds '" + model_ + "'");
  model_ = model;
  opened_ = Clock::now();
  open_version(catalogue_entry(http_->get("/models"), model_));
  await_open();
}

void MultilevelClient::start_open(const std::string& model) {
  if (loader_ || opening_) fail("open", "this client already holds '" + model_ + "'");
  model_ = model;
  opened_ = Clock::now();
  opening_ = std::make_unique<PendingGets>(std::vector<std::string>{"/models"});
}

// The catalogue (when the version is not known yet), then the version's entry and head; first, after a
// 410, the level GETs of the replaced version still on the wire, read and dropped.
bool MultilevelClient::poll_open() {
  if (loader_) return true;
  if (!opening_) fail("open", "no model being opened");
  http_->poll();
  while (!posted_.empty()) {
    if (!http_->take()) return false;
    posted_.pop_front();
  }
  if (!opening_->advance(*http_)) return false;
  const std::unique_ptr<PendingGets> done = std::move(opening_);
  if (done->targets().size() == 1) open_version(catalogue_entry(done->answers()[0], model_));
  else opened(done->targets(), done->answers());
  return poll_open();  // true once open, unless a 410 started another re-open
}

// Waits for the version being opened (free-running: the transport's non-blocking calls, as frames use it).
void MultilevelClient::await_open() {
  if (options_.free_running) {
    while (!poll_open()) http_->wait();
    return;
  }
  while (opening_) {  // again after a 410 in its answers
    const std::unique_ptr<PendingGets> done = std::move(opening_);
    opened(done->targets(), http_->get_all(done->targets()));
  }
}

// The GETs that open the version `entry` names (a progressive model's levels are derived: the same URLs).
void MultilevelClient::open_version(const nlohmann::json& entry) {
  version_ = entry_version(entry);
  std::vector<std::string> targets = {protocol::model_path(model_, version_) + "/multilevel",
                                      prefix(options_.compressed) + "head"};
  if (options_.free_running) targets.push_back(coarsest_target(prefix(options_.compressed)));
  opening_ = std::make_unique<PendingGets>(std::move(targets));
}

// A 410: the model was replaced under its name. Its levels are dropped and the version the 410 names
// opens as a new model; level GETs still on the wire are read and dropped first (poll_open).
void MultilevelClient::replaced(const std::string& target, const HttpAnswer& answer) {
  const nlohmann::json entry = reopens_.follow(target, answer, model_);
  loader_.reset();
  lod_.reset();
  switch_.reset();
  shown_ = -1;
  target_ = requested_ = 0;
  open_version(entry);
}

void MultilevelClient::opened(const std::vector<std::string>& targets, const std::vector<HttpAnswer>& answers) {
  for (size_t i = 0; i < answers.size(); ++i)
    if (answers[i].status == 410) return replaced(targets[i], answers[i]);
  const std::string& target = targets[1];
  read_entry(model_, targets[0], answers[0]);
  const HttpAnswer& head = answers[1];
  if (head.status != 200) refused(target, head);
  loader_.emplace("GET " + target, head.body, options_.limits,
                  options_.compressed ? MultilevelForm::compressed : MultilevelForm::plain);
  if (loader_->level_count() != lod_triangles_.size()) fail("GET " + target, "its level count is not the catalogue's");
  lod_.emplace(loader_->mesh());
  if (answers.size() > 2) {
    add(targets[2], answers[2]);
    lod_.emplace(loader_->mesh());
  }
  requested_ = loader_->finest_loaded();
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

void MultilevelClient::set_rule(float tolerance, uint64_t budget, uint32_t morph_frames) {
  options_.tolerance = tolerance;
  options_.budget = budget;
  // A switch under way is a number of frames out of the old length: end it where it was going.
  if (switch_ && morph_frames != options_.morph_frames) {
    lod_->set_level(switch_->to);
    shown_ = float(switch_->to);
    switch_.reset();
  }
  options_.morph_frames = morph_frames;
}

// GETs the levels still missing down to `level`, pipelined, and adds each as it arrives. Returns how many.
uint32_t MultilevelClient::load_to(uint32_t level) {
  if (loader_->complete() || loader_->finest_loaded() <= level) return 0;
  std::vector<std::string> targets;
  for (uint32_t l = loader_->finest_loaded(); l-- > level;) targets.push_back(level_target(prefix(options_.compressed), l));
  uint32_t added = 0;
  http_->get_all(targets, [&](size_t index, HttpAnswer&& answer) {
    if (!opening_) added += add(targets[index], answer);  // else a 410 came: the rest is the old version's
  });
  if (!opening_) lod_.emplace(loader_->mesh());  // the structure grew: nothing cached of it is kept
  return added;
}

// The event "a level arrived" (the next one, coarsest first): added and its arrival kept, no I/O. False
// for a 410: the model was replaced, and the version it names is opening.
bool MultilevelClient::add(const std::string& target, const HttpAnswer& answer) {
  if (answer.status == 410) {
    replaced(target, answer);
    return false;
  }
  if (answer.status != 200) refused(target, answer);
  reopens_.refill();
  const uint32_t l = loader_->next_level();
  loader_->add_level("GET " + target, answer.body);
  const HttpCounters& c = http_->counters();
  arrivals_.push_back({l, answer.body.size(), c.bytes_down, c.payload_down, ms_since(opened_)});
  return true;
}

// Free-running: every level fully arrived, added without waiting for one. Returns how many.
uint32_t MultilevelClient::add_arrived(MultilevelFrame& out) {
  uint32_t added = 0;
  while (!opening_) {
    const std::optional<HttpAnswer> answer = http_->take();
    if (!answer) break;
    const std::string target = std::move(posted_.front());
    posted_.pop_front();
    if (!add(target, *answer)) break;
    out.report.latency_ms = ms_since(answer->sent_at);
    ++added;
  }
  if (added > 0 && !opening_) lod_.emplace(loader_->mesh());
  return added;
}

// Free-running: the levels not yet asked for down to `level`, coarsest first, as many as the pipe takes;
// the rest wait for a later frame, which asks only for what its own rule wants.
void MultilevelClient::request_to(uint32_t level) {
  while (requested_ > level && http_->room() > 0) {
    posted_.push_back(level_target(prefix(options_.compressed), --requested_));
    http_->post(posted_.back());
  }
}

void MultilevelClient::show(float level, MultilevelFrame& out) {
  const auto start = Clock::now();
  if (level == std::floor(level)) lod_->set_level(uint32_t(level));
  else lod_->set_level(level);
  out.lod_ms = ms_since(start);
  shown_ = level;
}

// The switch's geomorph at its current frame: LOD `to` once it is done.
void MultilevelClient::show_switch(MultilevelFrame& out) {
  const auto start = Clock::now();
  const LodSwitch& s = *switch_;
  if (s.frame >= options_.morph_frames) {
    lod_->set_level(s.to);
    switch_.reset();
  } else {
    // t runs from LOD `from` to LOD `to`; geomorph's t weighs the finer of the two.
    const float done = float(s.frame) / float(options_.morph_frames);
    lod_->geomorph(std::min(s.from, s.to), std::max(s.from, s.to), s.to < s.from ? done : 1 - done);
  }
  out.lod_ms = ms_since(start);
  shown_ = lod_->level();
}

// The wanted level, or the finest loaded if coarser (the target): one geomorph from the level shown straight
// to it over morph_frames frames (gueziec et al. blend the two LODs of one switch, whatever lies between).
// A switch runs to its end before the next starts, unless the target goes back to where it came from,
// which reverses it.
void MultilevelClient::step_to(uint32_t wanted, MultilevelFrame& out) {
  target_ = std::max(wanted, loader_->finest_loaded());
  if (options_.morph_frames == 0 || shown_ < 0) {
    show(float(target_), out);
    return;
  }
  if (switch_ && switch_->from == target_) {
    std::swap(switch_->from, switch_->to);
    switch_->frame = options_.morph_frames - switch_->frame;
  }
  if (!switch_ && float(target_) != shown_) switch_ = LodSwitch{uint32_t(shown_), target_, 0};
  if (!switch_) {
    show(shown_, out);
    return;
  }
  ++switch_->frame;
  show_switch(out);
}

bool MultilevelClient::in_motion() const { return switch_.has_value() || (opened() && shown_ != float(target_)); }

MultilevelFrame MultilevelClient::frame(const Camera& camera) {
  if (!loader_) fail("stream", "no model open");
  MultilevelFrame out;
  out.report.frame = ++frame_;
  const HttpCounters before = http_->counters();
  out.wanted_level = wanted_level(camera);
  if (options_.free_running) {
    http_->poll();
    out.report.vsplits = add_arrived(out);
    if (opening_) {  // a 410: the version it names opens over the next frames (poll_open)
      poll_open();
      return out;
    }
    request_to(out.wanted_level);
    http_->poll();  // the GETs just handed over start on their way
    out.report.requested = !posted_.empty();
  } else {
    const auto start = Clock::now();
    out.report.vsplits = load_to(out.wanted_level);
    if (opening_) {  // a 410: this frame again on the version it names
      await_open();
      --frame_;
      return frame(camera);
    }
    if (out.report.vsplits > 0) {
      out.report.requested = true;
      out.report.latency_ms = ms_since(start);
    }
  }
  step_to(out.wanted_level, out);
  const HttpCounters& after = http_->counters();
  out.report.up_bytes = after.bytes_up - before.bytes_up;
  out.report.down_bytes = after.bytes_down - before.bytes_down;
  out.payload_down = after.payload_down - before.payload_down;
  out.report.faces = lod_->indices().size() / 3;
  out.level = lod_->level();
  out.levels_loaded = loader_->levels_loaded();
  out.in_flight = uint32_t(posted_.size());
  return out;
}

// Waits for the levels down to `wanted` and for every GET still on the wire (a finer level an earlier
// camera asked for is added too, as lock-step would have loaded it).
void MultilevelClient::settle_free(uint32_t wanted) {
  MultilevelFrame ignored;
  for (;;) {
    request_to(wanted);
    if (posted_.empty()) return;
    http_->wait();
    add_arrived(ignored);
    if (opening_) await_open();
  }
}

void MultilevelClient::settle(const Camera& camera) {
  if (opening_) await_open();
  if (!loader_) fail("stream", "no model open");
  const uint32_t wanted = wanted_level(camera);
  if (options_.free_running) settle_free(wanted);
  else load_to(wanted);
  if (opening_) {  // a 410 among the levels
    await_open();
    return settle(camera);
  }
  MultilevelFrame ignored;
  switch_.reset();
  target_ = std::max(wanted, loader_->finest_loaded());
  show(float(target_), ignored);
}

}  // namespace pms::client
