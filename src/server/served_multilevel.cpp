// A multilevel model's resources, cut and hashed once (served_multilevel.h).
#define XXH_INLINE_ALL
#include <xxhash.h>
#include <algorithm>
#include <cmath>
#include <filesystem>

#include "multilevel/codec.h"
#include "multilevel/file.h"
#include "multilevel/loader.h"
#include "multilevel/mesh.h"
#include "protocol/url_segment.h"
#include "server/http_answers.h"
#include "server/served_multilevel.h"

namespace pms::server {
namespace {

// Strong: the bytes' own hash with the canonical URL, so one URL has one ETag whatever process serves it.
std::string etag_of(const std::vector<uint8_t>& bytes, const std::string& resource) {
  const uint64_t hashes[2] = {XXH64(bytes.data(), bytes.size(), 0), XXH64(resource.data(), resource.size(), 0)};
  return etag_text(XXH64(hashes, sizeof hashes, 0));
}

// The binary form's bytes determine the compressed form's (on a fixed grid): their hash is the version.
std::string version_of(const MultilevelParts& parts) {
  std::vector<uint64_t> hashes = {XXH64(parts.head.data(), parts.head.size(), 0)};
  for (const auto& level : parts.levels) hashes.push_back(XXH64(level.data(), level.size(), 0));
  return protocol::model_version_text(XXH64(hashes.data(), hashes.size() * sizeof(uint64_t), 0));
}

using Bytes = std::shared_ptr<const std::vector<uint8_t>>;

// One form's head and levels (parts.levels is coarsest first) as resources under `prefix`, indexed by level.
void cut(MultilevelParts parts, const std::string& prefix, Bytes& head, std::string& head_etag,
         std::vector<Bytes>& levels, std::vector<std::string>& level_etags) {
  head_etag = etag_of(parts.head, prefix + "/head");
  head = std::make_shared<const std::vector<uint8_t>>(std::move(parts.head));
  const auto count = uint32_t(parts.levels.size());
  levels.resize(count);
  level_etags.resize(count);
  for (uint32_t i = 0; i < count; ++i) {
    const uint32_t level = count - 1 - i;
    level_etags[level] = etag_of(parts.levels[i], prefix + "/levels/" + std::to_string(level));
    levels[level] = std::make_shared<const std::vector<uint8_t>>(std::move(parts.levels[i]));
  }
}

void bounding_sphere(const MultilevelMesh& mesh, ServedMultilevel& out) {
  float lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
  const uint32_t d = mesh.dimension;
  for (uint32_t v = 0; v < mesh.vertices(); ++v)
    for (uint32_t k = 0; k < d; ++k) {
      const float p = mesh.positions[size_t(v) * d + k];
      lo[k] = v == 0 ? p : std::min(lo[k], p);
      hi[k] = v == 0 ? p : std::max(hi[k], p);
    }
  double sq = 0;
  for (int k = 0; k < 3; ++k) {
    out.center[k] = 0.5f * (lo[k] + hi[k]);
    sq += 0.25 * double(hi[k] - lo[k]) * (hi[k] - lo[k]);
  }
  out.radius = float(std::sqrt(sq));
}

}  // namespace

uint64_t ServedMultilevel::memory_bytes() const {
  uint64_t total = head->size() + compressed_head->size();
  for (const auto& level : levels) total += level->size();
  for (const auto& level : compressed_levels) total += level->size();
  return total;
}

std::unique_ptr<ServedMultilevel> open_multilevel(const std::string& path) {
  return serve_multilevel(read_multilevel(path), std::filesystem::path(path).stem().string(), path);
}

std::unique_ptr<ServedMultilevel> serve_multilevel(const MultilevelMesh& mesh, const std::string& name,
                                                   const std::string& path, const std::string& version) {
  auto out = std::make_unique<ServedMultilevel>();
  out->path = path;
  out->name = name;
  out->dimension = mesh.dimension;
  out->normals = !mesh.normals.empty();
  out->colors = !mesh.colors.empty();
  out->texcoords = !mesh.texcoords.empty();
  out->vertices = mesh.vertices();
  out->triangles = mesh.faces();
  MultilevelParts parts = multilevel_parts(mesh);
  out->version = version.empty() ? version_of(parts) : version;
  const std::string prefix = "/models/" + out->name + "/" + out->version;
  cut(std::move(parts), prefix, out->head, out->head_etag, out->levels, out->level_etags);
  out->position_bits = kDefaultPositionBits;
  cut(multilevel_compressed_parts(mesh, out->position_bits), prefix + "/compressed", out->compressed_head,
      out->compressed_head_etag, out->compressed_levels, out->compressed_level_etags);
  out->lod_vertices = mesh.vertex_count;
  out->lod_triangles = mesh.triangle_count;
  out->level_errors = multilevel_level_errors(mesh);
  bounding_sphere(mesh, *out);
  return out;
}

}  // namespace pms::server
