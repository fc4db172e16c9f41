// GET /models/{m}/[compressed/]head and /models/{m}/[compressed/]levels/{level} (multilevel_routes.h):
// bytes cut once at start (served_multilevel.h), answered without a copy.
#include "server/multilevel_routes.h"

#define XXH_INLINE_ALL
#include <xxhash.h>

#include <nlohmann/json.hpp>
#include <vector>

#include "server/http_answers.h"

namespace pms::server {
namespace {

HttpAnswer shared_answer(const HttpRequest& request, const std::string& etag,
                         const std::shared_ptr<const std::vector<uint8_t>>& bytes) {
  HttpAnswer answer = fresh(request, etag, "application/octet-stream");
  if (answer.status == 200) answer.shared = bytes;
  return answer;
}

// Coarsest first, as a client loads them.
template <typename T>
nlohmann::json coarsest_first(const std::vector<T>& per_level) {
  return nlohmann::json(std::vector<T>(per_level.rbegin(), per_level.rend()));
}

// The model's catalogue entry alone: what a client of a model whose GET /models entry is "progressive"
// reads to stream its derived levels.
HttpAnswer entry_answer(const ServedMultilevel& model, const HttpRequest& request) {
  const std::string text = multilevel_entry(model).dump() + "\n";
  HttpAnswer answer = fresh(request, etag_text(XXH64(text.data(), text.size(), 0)), "application/json");
  if (answer.status == 200) answer.owned.assign(text.begin(), text.end());
  return answer;
}

}  // namespace

HttpAnswer multilevel_route(const ServedMultilevel& model, const HttpRequest& request,
                            std::span<const std::string_view> segments) {
  // /models/{m}/compressed/... names the same resources in the compressed form.
  const bool compressed = segments.size() >= 3 && segments[2] == "compressed";
  std::vector<std::string_view> s(segments.begin(), segments.end());
  if (compressed) s.erase(s.begin() + 2);
  const bool head = s.size() == 3 && s[2] == "head", level = s.size() == 4 && s[2] == "levels";
  const bool entry = !compressed && s.size() == 3 && s[2] == "multilevel";
  if (!head && !level && !entry)
    return error_answer(404, "model '" + model.name +
                                 "' as a multilevel mesh: its resources are /multilevel, /head and /levels/LEVEL, "
                                 "and /compressed/head and /compressed/levels/LEVEL");
  if (request.method != "GET" && request.method != "HEAD") return method_not_allowed("GET, HEAD");
  if (entry) return entry_answer(model, request);
  if (head)
    return compressed ? shared_answer(request, model.compressed_head_etag, model.compressed_head)
                      : shared_answer(request, model.head_etag, model.head);
  // "coarsest" names level count - 1 for a client that does not know the count yet (docs/protocol.md).
  uint64_t l = model.level_count() - 1;
  if (s[3] != "coarsest" && !parse_decimal(s[3], l))
    return error_answer(400, "a level is /models/M/levels/LEVEL in plain decimal, or /levels/coarsest");
  if (l >= model.level_count())
    return error_answer(404, "model '" + model.name + "' has levels 0 to " + std::to_string(model.level_count() - 1));
  return compressed ? shared_answer(request, model.compressed_level_etags[l], model.compressed_levels[l])
                    : shared_answer(request, model.level_etags[l], model.levels[l]);
}

nlohmann::json multilevel_entry(const ServedMultilevel& m) {
  std::vector<uint64_t> level_bytes, compressed_bytes;
  for (const auto& bytes : m.levels) level_bytes.push_back(bytes->size());
  for (const auto& bytes : m.compressed_levels) compressed_bytes.push_back(bytes->size());
  return {{"name", m.name},
          {"kind", "multilevel"},
          {"version", m.version},
          {"levels", m.level_count()},
          {"dimension", m.dimension},
          {"normals", m.normals},
          {"colors", m.colors},
          {"texcoords", m.texcoords},
          {"vertices", m.vertices},
          {"faces", m.triangles},
          {"lod_vertices", coarsest_first(m.lod_vertices)},
          {"lod_triangles", coarsest_first(m.lod_triangles)},
          {"level_bytes", coarsest_first(level_bytes)},
          {"compressed_level_bytes", coarsest_first(compressed_bytes)},
          {"position_bits", m.position_bits},
          {"level_errors", coarsest_first(m.level_errors)},
          {"center", m.center},
          {"radius", m.radius}};
}

}  // namespace pms::server
