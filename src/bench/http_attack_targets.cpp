#include "bench/http_attack_targets.h"

#include <vector>

#include "apps/camera_path.h"
#include "bench/child_process.h"
#include "common/error.h"
#include "protocol/base64url.h"
#include "protocol/split_request.h"
#include "protocol/url_segment.h"
#include "server/catalogue.h"
#include "spm/pms_file.h"

namespace pms::bench {
namespace {

constexpr uint32_t kMinIds = 1024;

// The internal nodes of the shallowest level that has at least kMinIds of them.
std::vector<uint32_t> widest_level(const ModelData& model) {
  std::vector<uint32_t> level;
  for (uint32_t r = 0; r < model.root_count; ++r) level.push_back(r);
  while (!level.empty()) {
    std::vector<uint32_t> internal, next;
    for (uint32_t n : level) {
      if (model.is_leaf(n)) continue;
      internal.push_back(n);
      next.push_back(model.first_child[n]);
      next.push_back(model.first_child[n] + 1);
    }
    if (internal.size() >= kMinIds) return internal;
    level = std::move(next);
  }
  fail("attacks", "the model has no level of " + std::to_string(kMinIds) + " internal nodes");
}

// Split records in the bands of `ids` down to `depth` levels below them.
uint64_t band_splits(const ModelData& model, const std::vector<uint32_t>& ids, uint32_t depth) {
  uint64_t splits = 0;
  std::vector<uint32_t> level = ids;
  for (uint32_t d = 0; d <= depth && !level.empty(); ++d) {
    std::vector<uint32_t> next;
    for (uint32_t n : level) {
      if (model.is_leaf(n)) continue;
      ++splits;
      next.push_back(model.first_child[n]);
      next.push_back(model.first_child[n] + 1);
    }
    level = std::move(next);
  }
  return splits;
}

std::string target_of(const ModelData& model, const std::string& prefix, const std::vector<uint32_t>& ids,
                      uint32_t depth) {
  protocol::SplitRequest request;
  request.depth = depth;
  for (uint32_t n : ids) request.ids.push_back(model.id(n));
  return prefix + "/splits/" + protocol::base64url_encode(protocol::encode_split_request(request));
}

}  // namespace

ExpensiveRequest most_expensive_request(const ModelData& model, const std::string& prefix, uint32_t max_ids,
                                        uint32_t max_depth, uint64_t max_splits, size_t max_url_bytes) {
  std::vector<uint32_t> ids = widest_level(model);
  if (ids.size() > max_ids) ids.resize(max_ids);
  // Fewer ids until the URL fits (the code of one level's ids takes about 5 bits an id).
  while (ids.size() > kMinIds && target_of(model, prefix, ids, 0).size() > max_url_bytes)
    ids.resize(std::max<size_t>(kMinIds, ids.size() * 9 / 10));
  ExpensiveRequest best;
  for (uint32_t depth = 0; depth <= max_depth; ++depth) {
    const uint64_t splits = band_splits(model, ids, depth);
    if (splits > max_splits) break;
    best = {"", uint32_t(ids.size()), depth, splits};
  }
  best.target = target_of(model, prefix, ids, best.depth);
  if (best.target.size() > max_url_bytes) fail("attacks", "the expensive request's URL is over the limit");
  return best;
}

std::string build_terrain(const std::string& pmstream_exe, const std::filesystem::path& dir, uint64_t faces) {
  const std::string pms = (dir / "terrain.pms").string();
  const ChildResult run = run_child({pmstream_exe, "build", "terrain:" + std::to_string(faces), "-o", pms});
  if (!run.ok()) fail("pmstream build terrain", run.failure());
  return pms;
}

AttackSetup attack_setup(const std::string& pmstream_exe, const std::string& pms, uint32_t frames, float tolerance) {
  const std::unique_ptr<PmsFile> file = PmsFile::open(pms);
  AttackSetup setup;
  setup.pmstream_exe = pmstream_exe;
  setup.model_pms = pms;
  setup.model_name = std::filesystem::path(pms).stem().string();
  // The URLs of the model as `serve` on its default grid names them.
  setup.model_path = protocol::model_path(
      setup.model_name, server::content_version(file->content_checksum(), protocol::kDefaultPositionBits));
  app::PathOptions options;
  options.frames = frames;
  setup.path = app::make_camera_path(app::PathKind::orbit, file->model(), options);
  setup.tolerance = tolerance;
  const ExpensiveRequest expensive = most_expensive_request(file->model(), setup.model_path);
  setup.expensive = expensive.target;
  setup.expensive_note = std::to_string(expensive.ids) + " ids, depth " + std::to_string(expensive.depth) + ": " +
                         std::to_string(expensive.splits) + " splits, a " + std::to_string(expensive.target.size()) +
                         "-byte URL";
  return setup;
}

}  // namespace pms::bench
