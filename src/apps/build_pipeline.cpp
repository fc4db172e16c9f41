#include "apps/build_pipeline.h"

#include <cstdlib>
#include <filesystem>
#include <string_view>

#include "apps/resource_usage.h"
#include "common/error.h"
#include "io/shapes.h"
#include "spm/pms_file.h"

namespace pms::app {

std::string describe(const CleanReport& r) {
  std::string s;
  auto add = [&](size_t count, const char* what) {
    if (count == 0) return;
    if (!s.empty()) s += ", ";
    s += std::to_string(count) + " " + what;
  };
  add(r.welded_vertices, "coincident vertices welded");
  add(r.unreferenced_vertices, "unreferenced vertices dropped");
  add(r.degenerate_faces, "degenerate faces dropped");
  add(r.duplicate_faces, "duplicate faces dropped");
  add(r.nonmanifold_edges, "non-manifold edges cut");
  add(r.nonmanifold_vertices, "non-manifold vertices split");
  add(r.flipped_faces, "faces reoriented");
  if (r.inside_out_components > 0)
    add(r.inside_out_components, (std::string(r.inside_out_components == 1 ? "closed component" : "closed components") +
                                  " turned outward (" + std::to_string(r.inside_out_faces) + " faces)")
                                     .c_str());
  return s.empty() ? "nothing to repair" : s;
}

BuildRun build_mesh(Mesh mesh, const std::string& input_name, const std::string& out_path,
                    const BuildOptions& options) {
  BuildRun run;
  run.texcoords_dropped = mesh.has_texcoords();
  mesh.texcoords = {};  // .pms has no place for them (docs/pms-format.md); nothing below reads them
  Stopwatch clean_time;
  report(options.progress, "clean", 0);
  run.clean = clean_mesh(mesh);
  run.clean_seconds = clean_time.seconds();
  Stopwatch build_time;
  BuildResult built = build_progressive_mesh(mesh, options);
  mesh = {};  // the hierarchy holds what the file needs; the split records' coding wants the memory
  built.stats.input_name = input_name;
  built.stats.tool_version = PMSTREAM_VERSION;
  built.stats.clean_report = describe(run.clean);
  report(options.progress, "write", 0);
  Stopwatch write_time;
  write_pms(out_path, built.hierarchy, built.stats);
  run.write_seconds = write_time.seconds();
  run.build_seconds = build_time.seconds();
  run.stats = built.stats;
  run.output_bytes = std::filesystem::file_size(out_path);
  return run;
}

namespace {

// "terrain:FACES" names the built-in procedural terrain instead of a file; "terrain:FACES:colors" the same
// terrain with land colours (the demo's). The plain spelling keeps the uncoloured mesh that tests and
// benches compare byte for byte.
bool parse_terrain_spec(const std::string& spec, uint64_t& faces, TerrainColors& colors) {
  constexpr std::string_view prefix = "terrain:", colored = ":colors";
  if (spec.rfind(prefix, 0) != 0) return false;
  std::string count = spec.substr(prefix.size());
  colors = TerrainColors::none;
  if (count.size() > colored.size() && count.ends_with(colored)) {
    count.resize(count.size() - colored.size());
    colors = TerrainColors::land;
  }
  char* end = nullptr;
  const unsigned long long value = std::strtoull(count.c_str(), &end, 10);
  if (count.empty() || *end != '\0' || value < 2 || value > 200'000'000)
    fail(spec, "expected terrain:FACES or terrain:FACES:colors with FACES between 2 and 200000000");
  faces = value;
  return true;
}

}  // namespace

Mesh load_input(const std::string& in_path, const ProgressFn& progress) {
  uint64_t faces = 0;
  TerrainColors colors{};
  if (parse_terrain_spec(in_path, faces, colors)) return make_terrain(faces, 1, colors);
  return load_mesh(in_path, progress);
}

BuildRun build_file(const std::string& in_path, const std::string& out_path, const BuildOptions& options,
                    AfterBuild after) {
  const BuildMemoryTuning tuning(after);
  Stopwatch load_time;
  Mesh mesh = load_input(in_path, options.progress);
  const double load_seconds = load_time.seconds();
  BuildRun run = build_mesh(std::move(mesh), std::filesystem::path(in_path).filename().string(), out_path, options);
  run.load_seconds = load_seconds;
  return run;
}

nlohmann::json stats_json(const BuildStats& s) {
  return {{"input_vertices", s.input_vertices}, {"input_faces", s.input_faces}, {"base_vertices", s.base_vertices},
          {"base_faces", s.base_faces},         {"vsplits", s.vsplits},         {"tree_id_bits", s.tree_id_bits},
          {"node_id_bits", s.node_id_bits},     {"max_depth", s.max_depth}};
}

nlohmann::json build_json(const BuildRun& run, double seconds, double peak_rss_mb) {
  nlohmann::json j = stats_json(run.stats);
  j["seconds"] = seconds;
  j["load_seconds"] = run.load_seconds;
  j["clean_seconds"] = run.clean_seconds;
  j["build_seconds"] = run.build_seconds;  // the hierarchy and the write
  j["write_seconds"] = run.write_seconds;  // the .pms file: validation, split records, the bytes
  j["peak_rss_mb"] = peak_rss_mb;
  j["output_bytes"] = run.output_bytes;
  j["clean"] = describe(run.clean);
  j["texcoords_dropped"] = run.texcoords_dropped;
  return j;
}

}  // namespace pms::app
