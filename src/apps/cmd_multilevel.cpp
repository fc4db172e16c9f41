// pmstream multilevel build IN -o OUT.pml [--levels L] [--cluster grid:N,...|FILE.json] [--ascii]
//                            [--base-vertices N] [--json]
// pmstream multilevel info FILE [--json]
// pmstream multilevel level FILE --level X -o OUT.ply
// pmstream multilevel level FILE (--region x0,y0,z0,x1,y1,z1 | --sphere x,y,z,r) [--level X] -o OUT.ply
// pmstream multilevel level FILE --camera CAM.json [--pixels P] -o OUT.ply
// Progressive multilevel meshes (gueziec et al. 1999; docs/multilevel-format.md, docs/cli.md).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "apps/build_pipeline.h"
#include "apps/camera_json.h"
#include "apps/commands.h"
#include "apps/progress_bar.h"
#include "apps/resource_usage.h"
#include "builder/build.h"
#include "common/error.h"
#include "io/mesh.h"
#include "multilevel/build.h"
#include "multilevel/cluster.h"
#include "multilevel/codec.h"
#include "multilevel/file.h"
#include "multilevel/local.h"
#include "multilevel/mesh.h"
#include "multilevel/region.h"

namespace pms::app {
namespace {

struct MultilevelBuildArgs {
  std::string input, output;
  uint32_t levels = 0;
  uint64_t base_vertices = BuildOptions{}.base_vertices;
  std::string cluster;  // "grid:N,..." or empty: the builder's collapses
  bool ascii = false, json = false;
};

// "grid:64,16,4" -> {64, 16, 4}.
std::vector<uint32_t> grid_resolutions(const std::string& spec) {
  const std::string prefix = "grid:";
  std::vector<uint32_t> cells;
  size_t at = prefix.size();
  while (at <= spec.size()) {
    const size_t comma = std::min(spec.find(',', at), spec.size());
    const std::string item = spec.substr(at, comma - at);
    char* end = nullptr;
    const unsigned long n = std::strtoul(item.c_str(), &end, 10);
    if (item.empty() || *end != '\0' || n == 0 || n > (1u << 20))
      fail("--cluster", "'" + item + "' is not a grid size from 1 to 2^20");
    if (!cells.empty() && n >= cells.back()) fail("--cluster", "grid sizes must decrease (finest first)");
    cells.push_back(uint32_t(n));
    at = comma + 1;
  }
  return cells;
}

// A clustering file: {"clusterings": [{"cluster": [one cluster per input vertex], "positions": [x, y, z per
// cluster]}, ...]}, finest first (docs/cli.md, "multilevel").
std::vector<VertexClustering> clusterings_from_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) fail(path, "cannot open the clustering file");
  try {
    const nlohmann::json j = nlohmann::json::parse(in);
    std::vector<VertexClustering> out;
    for (const auto& c : j.at("clusterings")) {
      VertexClustering clustering;
      clustering.cluster = c.at("cluster").get<std::vector<uint32_t>>();
      clustering.positions = c.at("positions").get<std::vector<float>>();
      if (clustering.positions.size() % 3)
        fail(path, "clustering " + std::to_string(out.size()) + ": positions are not x, y, z triples");
      out.push_back(std::move(clustering));
    }
    return out;
  } catch (const nlohmann::json::exception& e) {
    fail(path, std::string("not a clustering file: ") + e.what());
  }
}

std::vector<VertexClustering> clusterings_of(const Mesh& mesh, const std::string& spec) {
  if (spec.rfind("grid:", 0) == 0) return grid_clusterings(mesh, grid_resolutions(spec));
  return clusterings_from_file(spec);
}

// Where the levels come from: the builder's collapses of the cleaned mesh, or grid clusterings of the mesh
// as loaded (non-manifold allowed, so it is not cleaned).
struct LevelSource {
  MultilevelMesh ml;
  std::string clean_report = "not cleaned (clustering input may be non-manifold)";
  uint64_t operations = 0;  // collapses or clusterings
  double source_seconds = 0, multilevel_seconds = 0;
};

LevelSource multilevel_of(Mesh mesh, const MultilevelBuildArgs& args, const ProgressFn& progress) {
  LevelSource out;
  if (!args.cluster.empty()) {
    Stopwatch cluster_time;
    const std::vector<VertexClustering> clusterings = clusterings_of(mesh, args.cluster);
    out.source_seconds = cluster_time.seconds();
    Stopwatch ml_time;
    out.ml = build_multilevel_from_clusterings(mesh, clusterings, args.levels);
    out.multilevel_seconds = ml_time.seconds();
    out.operations = clusterings.size();
    return out;
  }
  const BuildMemoryTuning tuning(AfterBuild::kExit);  // a builder's process from here (apps/build_memory.h)
  out.clean_report = describe(clean_mesh(mesh));
  BuildOptions options;
  options.base_vertices = args.base_vertices;
  options.progress = progress;
  Stopwatch pm_time;
  const BuildResult built = build_progressive_mesh(mesh, options);
  out.source_seconds = pm_time.seconds();
  Stopwatch ml_time;
  const std::vector<EdgeCollapse> collapses = collapses_of(built.hierarchy);
  out.ml = build_multilevel(mesh, collapses, args.levels);
  out.multilevel_seconds = ml_time.seconds();
  out.operations = collapses.size();
  return out;
}

void run_multilevel_build(const MultilevelBuildArgs& args, bool base_vertices_given) {
  // Both forms read back by their magic whatever the name; serve finds the models by ".pml".
  if (args.ascii) require_extension("--output", args.output, {".pml", ".txt"}, "the ASCII multilevel form");
  else require_extension("--output", args.output, {".pml"}, "the binary multilevel form (--ascii for the ASCII one)");
  if (base_vertices_given && !args.cluster.empty())
    fail("--base-vertices", "not used with --cluster (the clusterings give the levels, not the builder)");
  Stopwatch total;
  ProgressBar bar(!args.json);
  Stopwatch load_time;
  Mesh mesh = load_input(args.input, bar.callback());
  const double load_seconds = load_time.seconds();
  const LevelSource source = multilevel_of(std::move(mesh), args, bar.callback());
  bar.finish();
  const MultilevelMesh& ml = source.ml;
  const double pm_seconds = source.source_seconds, ml_seconds = source.multilevel_seconds;
  const char* operations = args.cluster.empty() ? "collapses" : "clusterings";
  Stopwatch write_time;
  write_multilevel(args.output, ml, args.ascii);
  const double write_seconds = write_time.seconds();
  const uint64_t bytes = std::filesystem::file_size(args.output);
  const bool dropped = args.ascii && (!ml.normals.empty() || !ml.colors.empty() || !ml.texcoords.empty());
  const uint64_t morph = geomorph_representative_count(ml);
  const uint64_t written = ml.stored_representatives() - (args.ascii ? morph : 0);
  if (args.json) {
    nlohmann::json j = {{"input", args.input},
                        {"output", args.output},
                        {"format", args.ascii ? "ascii" : "binary"},
                        {"vertices", ml.vertices()},
                        {"triangles", ml.faces()},
                        {"levels", ml.level_count()},
                        {operations, source.operations},
                        {"representatives", written},
                        {"geomorph_representatives", args.ascii ? 0 : morph},
                        {"geomorph_representatives_dropped", args.ascii ? morph : 0},
                        {"output_bytes", bytes},
                        {"attributes_dropped", dropped},
                        {"load_seconds", load_seconds},
                        {args.cluster.empty() ? "collapse_seconds" : "cluster_seconds", pm_seconds},
                        {"multilevel_seconds", ml_seconds},
                        {"write_seconds", write_seconds},
                        {"seconds", total.seconds()},
                        {"peak_rss_mb", peak_rss_mb()}};
    std::printf("%s\n", j.dump().c_str());
    return;
  }
  std::printf("%s -> %s (%s)\n", args.input.c_str(), args.output.c_str(), args.ascii ? "ASCII" : "binary");
  std::printf("  cleaning:        %s\n", source.clean_report.c_str());
  std::printf("  mesh:            %u vertices, %u triangles; %llu %s\n", ml.vertices(), ml.faces(),
              (unsigned long long)source.operations, operations);
  std::printf("  levels:          %u (coarsest: %u vertices, %u triangles)\n", ml.level_count(), ml.vertex_count.back(),
              ml.triangle_count.back());
  std::printf("  representatives: %llu stored (%llu only for geomorphs)\n", (unsigned long long)written,
              (unsigned long long)(args.ascii ? 0 : morph));
  std::printf("  time:            %.2f s (load %.2f, %s %.2f, multilevel %.3f, write %.3f)\n", total.seconds(),
              load_seconds, operations, pm_seconds, ml_seconds, write_seconds);
  std::printf("  output:          %llu bytes\n", (unsigned long long)bytes);
  if (dropped)
    std::printf(
        "  note:            the ASCII form has no normals, colours or texture coordinates; they were left out\n");
  if (args.ascii && morph)
    std::printf(
        "  note:            the ASCII form has no place for the %llu representatives only geomorphs use;"
        " they were left out\n",
        (unsigned long long)morph);
}

// Milliseconds of a set_level jump to `level` from the opposite end, and of a geomorph frame there: the
// fastest of a few tries, so that a busy machine's preemptions do not count.
struct SwitchTimes {
  double jump_ms = 1e300, morph_ms = 0;
};

SwitchTimes time_switches(const MultilevelMesh& m, uint32_t level) {
  MultilevelLod lod(m);
  SwitchTimes t;
  const uint32_t other_end = level < m.level_count() / 2 ? m.level_count() - 1 : 0u;
  for (int i = 0; i < 5; ++i) {
    lod.set_level(other_end);
    Stopwatch jump;
    lod.set_level(level);
    t.jump_ms = std::min(t.jump_ms, jump.seconds() * 1e3);
  }
  if (level + 1 < m.level_count()) {
    t.morph_ms = 1e300;
    lod.set_level(float(level) + 0.25f);  // connectivity and morph sources for this pair of levels
    for (int i = 0; i < 5; ++i) {
      Stopwatch morph;
      lod.set_level(float(level) + 0.1f * float(i + 3));
      t.morph_ms = std::min(t.morph_ms, morph.seconds() * 1e3);
    }
  }
  return t;
}

void run_multilevel_info(const std::string& path, bool json) {
  const MultilevelMesh m = read_multilevel(path);
  const uint64_t bytes = std::filesystem::file_size(path);
  const std::vector<uint32_t> reps = representatives_per_level(m), morph = geomorph_representatives_per_level(m);
  std::vector<CompressedLevelBits> bits;  // coarsest first, like the rows
  const MultilevelParts compressed = multilevel_compressed_parts(m, kDefaultPositionBits, &bits);
  uint64_t compressed_bytes = compressed.head.size();
  nlohmann::json levels = nlohmann::json::array();
  for (uint32_t l = m.level_count(); l-- > 0;) {
    const SwitchTimes t = time_switches(m, l);
    const CompressedLevelBits& b = bits[levels.size()];
    compressed_bytes += compressed.levels[levels.size()].size();
    levels.push_back({{"level", l},
                      {"vertices", m.vertex_count[l]},
                      {"triangles", m.triangle_count[l]},
                      {"level_vertices", m.level_vertices(l)},
                      {"level_triangles", m.level_triangles(l)},
                      {"representatives", reps[l]},
                      {"geomorph_representatives", morph[l]},
                      {"set_level_ms", t.jump_ms},
                      {"geomorph_ms", t.morph_ms},
                      {"compressed_bytes", compressed.levels[levels.size()].size()},
                      {"compressed_bits",
                       {{"header", b.header},
                        {"representatives", b.representatives},
                        {"vertices", b.vertices},
                        {"triangles", b.triangles}}}});
  }
  if (json) {
    const nlohmann::json j = {{"file", path},
                              {"bytes", bytes},
                              {"dimension", m.dimension},
                              {"normals", !m.normals.empty()},
                              {"colors", !m.colors.empty()},
                              {"texcoords", !m.texcoords.empty()},
                              {"levels", m.level_count()},
                              {"vertices", m.vertices()},
                              {"triangles", m.faces()},
                              {"representatives", m.stored_representatives()},
                              {"geomorph_representatives", geomorph_representative_count(m)},
                              {"compressed_bytes", compressed_bytes},
                              {"position_bits", kDefaultPositionBits},
                              {"texcoord_bits", m.texcoords.empty() ? 0 : kDefaultTexcoordBits},
                              {"per_level", levels}};
    std::printf("%s\n", j.dump().c_str());
    return;
  }
  std::printf("%s (%llu bytes): %u levels, %u vertices, %u triangles, %uD%s%s%s\n", path.c_str(),
              (unsigned long long)bytes, m.level_count(), m.vertices(), m.faces(), m.dimension,
              m.normals.empty() ? "" : ", normals", m.colors.empty() ? "" : ", colors",
              m.texcoords.empty() ? "" : ", texture coordinates");
  std::printf("  representatives: %llu stored (%llu only for geomorphs)\n",
              (unsigned long long)m.stored_representatives(), (unsigned long long)geomorph_representative_count(m));
  std::printf("  compressed (%u-bit grid): %llu bytes, head and every level\n", kDefaultPositionBits,
              (unsigned long long)compressed_bytes);
  std::printf("  %5s %10s %10s %10s %10s %8s %8s %10s %10s\n", "level", "LOD verts", "LOD tris", "+verts", "+tris",
              "reps", "+morph", "setLevel", "geomorph");
  for (const auto& row : levels)
    std::printf("  %5u %10u %10u %10u %10u %8u %8u %8.3f ms %8.3f ms\n", row["level"].get<uint32_t>(),
                row["vertices"].get<uint32_t>(), row["triangles"].get<uint32_t>(),
                row["level_vertices"].get<uint32_t>(), row["level_triangles"].get<uint32_t>(),
                row["representatives"].get<uint32_t>(), row["geomorph_representatives"].get<uint32_t>(),
                row["set_level_ms"].get<double>(), row["geomorph_ms"].get<double>());
}

// --level X and, for a local refinement, where (gueziec et al. 1999, Fig. 15).
struct MultilevelLevelArgs {
  std::string input, output;
  double level = -1;  // unset: 0 for a local refinement, required otherwise
  std::vector<float> region, sphere;
  std::string camera;
  float pixels = 1.0f;
  bool local() const { return !region.empty() || !sphere.empty() || !camera.empty(); }
};

void check_level(const std::string& path, const MultilevelMesh& m, double level) {
  if (level >= 0 && level <= m.level_count() - 1) return;
  char text[96];
  std::snprintf(text, sizeof text, "level %g is outside 0..%u", level, m.level_count() - 1);
  fail(path, text);
}

std::vector<uint32_t> wanted_splits(const MultilevelLevelArgs& args, const MultilevelMesh& m,
                                    const MultilevelDag& dag) {
  if (!args.camera.empty()) {
    float lo[3], hi[3];
    for (int k = 0; k < 3; ++k) lo[k] = 1e30f, hi[k] = -1e30f;
    for (uint32_t v = 0; v < m.vertices(); ++v)
      for (uint32_t k = 0; k < m.dimension; ++k) {
        lo[k] = std::min(lo[k], m.positions[size_t(v) * m.dimension + k]);
        hi[k] = std::max(hi[k], m.positions[size_t(v) * m.dimension + k]);
      }
    if (m.dimension == 2) lo[2] = hi[2] = 0;
    return splits_for_view(m, dag, make_view(load_camera(args.camera), lo, hi), args.pixels);
  }
  Region region;
  if (!args.sphere.empty()) {
    region.sphere = true;
    std::copy_n(args.sphere.begin(), 3, region.lo);
    region.radius = args.sphere[3];
  } else {
    std::copy_n(args.region.begin(), 3, region.lo);
    std::copy_n(args.region.begin() + 3, 3, region.hi);
  }
  return splits_in_region(m, dag, region, uint32_t(args.level));
}

void run_local_refinement(const MultilevelLevelArgs& args, const MultilevelMesh& m) {
  Stopwatch dag_time;
  const MultilevelDag dag = build_multilevel_dag(m);
  const double dag_seconds = dag_time.seconds();
  Stopwatch refine_time;
  MultilevelRefinement refinement(dag);
  const std::vector<uint32_t> wanted = wanted_splits(args, m, dag);
  const size_t splits = refinement.refine_to(wanted).splits.size();
  const LocalMesh local = local_mesh(m, dag, refinement);
  const double refine_seconds = refine_time.seconds();
  save_ply(local.mesh, args.output);
  std::printf("%s local refinement -> %s: %zu vertices, %zu triangles\n", args.input.c_str(), args.output.c_str(),
              local.mesh.vertex_count(), local.mesh.face_count());
  std::printf("  DAG:    %u collapses, %llu edges, %.1f MB, built in %.3f s\n", dag.vertices - dag.top_vertices,
              (unsigned long long)dag.edge_count(), double(dag.memory_bytes()) / 1e6, dag_seconds);
  std::printf("  splits: %zu wanted, %zu made in topological order (%.3f s with the mesh)\n", wanted.size(), splits,
              refine_seconds);
  std::printf("  state:  %zu non-zero constraint counts in the hash tables, %.1f MB\n", refinement.constraint_entries(),
              double(refinement.memory_bytes()) / 1e6);
}

void run_multilevel_level(const MultilevelLevelArgs& args) {
  const MultilevelMesh m = read_multilevel(args.input);
  const double level = args.local() && args.level < 0 ? 0 : args.level;
  if (args.level < 0 && !args.local()) fail(args.input, "--level is required without --region, --sphere or --camera");
  check_level(args.input, m, level);
  if (args.local()) {
    if (level != std::floor(level)) fail(args.input, "a local refinement takes a whole --level");
    MultilevelLevelArgs whole = args;
    whole.level = level;
    run_local_refinement(whole, m);
    return;
  }
  MultilevelLod lod(m);
  if (level == std::floor(level)) lod.set_level(uint32_t(level));
  else lod.set_level(float(level));
  save_ply(lod_mesh(m, lod), args.output);
  std::printf("%s level %g -> %s: %u vertices, %zu triangles\n", args.input.c_str(), level, args.output.c_str(),
              lod.vertex_count(), lod.indices().size() / 3);
}

}  // namespace

void add_multilevel_command(CliCommand& app) {
  CliCommand cmd = app.subcommand("multilevel", "Progressive multilevel meshes (gueziec et al. 1999)");
  cmd.require_subcommand();

  auto b = std::make_shared<MultilevelBuildArgs>();
  CliCommand build = cmd.subcommand("build", "Build a multilevel mesh from the builder's edge collapses");
  build.option("input", b->input, "Input mesh (PLY, OBJ, OFF, STL, glTF/GLB; .gz/.xz), or terrain:FACES").required();
  build.option("-o,--output", b->output, "Output file (binary unless --ascii)").required();
  build.option("--levels", b->levels, "Merge consecutive levels down to this many (0: every level)").show_default();
  const CliOption base_vertices = build
                                      .option("--base-vertices", b->base_vertices,
                                              "Collapse until this many vertices are left (0: as far as possible)")
                                      .show_default();
  build.option("--cluster", b->cluster,
               "Levels from vertex clusterings instead of collapses: grid:N,... (N^3 cells each, finest first) or a "
               "JSON clustering file; the mesh is not cleaned, non-manifold results allowed");
  build.flag("--ascii", b->ascii, "Write the paper's ASCII form (Fig. 6) instead of the binary one");
  build.flag("--json", b->json, "Print one JSON object with the statistics");
  build.on_run([b, base_vertices] { run_multilevel_build(*b, base_vertices.given()); });

  auto info_path = std::make_shared<std::string>();
  auto info_json = std::make_shared<bool>(false);
  CliCommand info =
      cmd.subcommand("info", "Per level: the LOD's vertices and triangles, representatives, switch times");
  info.option("file", *info_path, "Multilevel file (ASCII or binary)").required();
  info.flag("--json", *info_json, "Print one JSON object");
  info.on_run([info_path, info_json] { run_multilevel_info(*info_path, *info_json); });

  auto l = std::make_shared<MultilevelLevelArgs>();
  CliCommand level =
      cmd.subcommand("level", "Write the LOD at a level (fractional: a geomorph) or a local refinement as PLY");
  level.option("file", l->input, "Multilevel file (ASCII or binary)").required();
  const CliOption level_option =
      level
          .option("--level", l->level,
                  "Level, 0 = finest; e.g. 2.5 is halfway from level 3 to level 2; with --region or --sphere, the "
                  "level inside it (default 0)")
          .non_negative();
  auto region = level.option("--region", l->region, "Refine the box x0,y0,z0,x1,y1,z1; the rest stays coarse")
                    .delimiter(',')
                    .expected(6);
  auto sphere = level.option("--sphere", l->sphere, "Refine the ball x,y,z,r; the rest stays coarse")
                    .delimiter(',')
                    .expected(4)
                    .excludes(region);
  const CliOption camera = level.option("--camera", l->camera, "Refine for the view of CAM.json (screen-size rule)")
                               .excludes(region)
                               .excludes(sphere);
  const CliOption pixels =
      level.option("--pixels", l->pixels, "With --camera: split collapses wider than this many pixels")
          .non_negative()
          .show_default();
  level.option("-o,--output", l->output, "Output .ply").required().writes({".ply"}, "PLY");
  // --level is the LOD, or the level inside a box or ball; a view picks its own levels.
  auto by_target = std::make_shared<std::vector<VariantOption>>(
      std::vector<VariantOption>{{level_option, {"--level", "--region", "--sphere"}}, {pixels, {"--camera"}}});
  level.on_run([l, by_target, region, sphere, camera] {
    const char* target = camera.given()   ? "--camera"
                         : sphere.given() ? "--sphere"
                         : region.given() ? "--region"
                                          : "--level";
    refuse_unused_options(*by_target, target, target == std::string("--level") ? "--level alone" : target);
    run_multilevel_level(*l);
  });
}

}  // namespace pms::app
