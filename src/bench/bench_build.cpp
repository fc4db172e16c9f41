// The "build" group: E12 (build time and peak memory per model) and E1 (hierarchy statistics,
// kim-lee-kobbelt 2005 §6.2 Table 1) on the shared models, measured beside Debian's OpenMesh VDPM
// tools (OpenMesh-mkbalancedpm, then OpenMesh-Analyzer for the view-dependent refinement info) on
// the same decompressed file; then a scaling series on the procedural terrain, to read off whether
// the cost per face grows no faster than log n. Every build runs in its own process so its peak RSS
// is its own (wait4 rusage). These machines' speed swings by tens of percent within minutes, so each
// measurement is the median of a few runs, ours and OpenMesh's taken in turn.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>

#include "apps/resource_usage.h"
#include "bench/bench.h"
#include "bench/child_process.h"
#include "bench/gnuplot.h"
#include "bench/openmesh_pm.h"
#include "bench/report.h"
#include "common/error.h"
#include "protocol/packet_bits.h"

namespace pms::bench {
using app::peak_rss_mb;
using app::Stopwatch;
namespace fs = std::filesystem;
using nlohmann::json;
namespace {

const std::vector<std::string> kDefaultModels = {"bunny", "horse", "feline", "skull", "dragon"};
const std::vector<uint64_t> kTerrainFaces = {100'000, 500'000, 2'000'000, 8'000'000};
constexpr size_t kQuickTerrainSteps = 2;
// Per child process. The dragon (871k faces) takes well under a minute with either tool; an hour
// only stops a build that hangs.
constexpr double kStepTimeoutSeconds = 3600;
constexpr const char* kMkBalancedPm = "OpenMesh-mkbalancedpm";
constexpr const char* kAnalyzer = "OpenMesh-Analyzer";
// Runs per measurement (one with --quick); the median run is reported, every time is in the JSON.
constexpr size_t kRuns = 3;

struct PaperRow {
  const char* model;
  uint32_t base_vertices, details, tree_bits, node_bits;
};
// kim-lee-kobbelt 2005, Table 1 ("Statistics of PMs with balanced vertex hierarchies").
constexpr PaperRow kPaperTable1[] = {{"bunny", 62, 34'772, 6, 16},
                                     {"horse", 75, 19'776, 7, 14},
                                     {"feline", 12, 49'852, 4, 28},
                                     {"skull", 146, 98'160, 8, 23},
                                     {"Buddha", 65, 545'557, 7, 25}};

// What `pmstream build --json` must print for the bench to use it (docs/cli.md, "build").
constexpr const char* kBuildFields[] = {"seconds",      "load_seconds",  "build_seconds", "peak_rss_mb",
                                        "output_bytes", "base_vertices", "vsplits",       "tree_id_bits",
                                        "node_id_bits", "input_faces",   "input_vertices"};

struct OurBuild {
  ChildResult run;
  json stats;  // the child's --json object, extended with what wait4 measured; null when it failed
  std::string error;
};

struct OpenMeshBuild {
  ChildResult mkbalancedpm, analyzer;
  std::optional<OpenMeshPmStats> pm;
  std::string reported_bits;  // mkbalancedpm's own "Bits for <tree-id, node-id>" line, to cross-check the parser
  std::string error;
};

struct ModelResult {
  std::string name;
  fs::path file;
  std::string error;                                   // the input could not be prepared: nothing ran
  OurBuild ours;                                       // the median run
  std::optional<OpenMeshBuild> openmesh;               // the median run; absent when the tools are not installed
  std::vector<double> ours_seconds, openmesh_seconds;  // every run's wall time (OpenMesh: both tools)
};

size_t runs(const BenchContext& context) { return context.options.quick ? 1 : kRuns; }

double openmesh_seconds(const OpenMeshBuild& build) {
  return build.mkbalancedpm.wall_seconds + build.analyzer.wall_seconds;
}

// The run with the median time (the upper one of an even count).
template <class Run>
Run median_run(std::vector<Run>& all, const std::vector<double>& seconds) {
  std::vector<size_t> order(all.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return seconds[a] < seconds[b]; });
  return std::move(all[order[order.size() / 2]]);
}

// Progress goes to stderr so stdout carries only the tables.
void progress_begin(const std::string& what) {
  std::fprintf(stderr, "bench: %s ... ", what.c_str());
  std::fflush(stderr);
}
void progress_end(const std::string& outcome) { std::fprintf(stderr, "%s\n", outcome.c_str()); }
void print(const std::string& text) {
  std::fputs(text.c_str(), stdout);
  std::fflush(stdout);
}

std::string step_outcome(const ChildResult& run) {
  if (!run.ok()) return "FAILED (" + run.failure() + ")";
  return fixed(run.wall_seconds, 2) + " s, peak " + fixed(run.peak_rss_mb, 0) + " MB";
}

ChildOptions step_options() {
  ChildOptions options;
  options.timeout_seconds = kStepTimeoutSeconds;
  return options;
}

// ---------------------------------------------------------------------------------------------
// The steps

OurBuild run_our_build(const BenchContext& context, const std::string& input, const fs::path& output) {
  OurBuild build;
  build.run = run_child({context.pmstream_exe, "build", input, "-o", output.string(), "--json"}, step_options());
  if (!build.run.ok()) {
    build.error = "pmstream build " + input + ": " + build.run.failure();
    return build;
  }
  json stats = json::parse(build.run.out, nullptr, /*allow_exceptions=*/false);
  if (stats.is_discarded() || !stats.is_object()) {
    build.error = "pmstream build " + input + " --json: output is not a JSON object";
    return build;
  }
  for (const char* field : kBuildFields) {
    if (!stats.contains(field) || !stats[field].is_number()) {
      build.error = "pmstream build " + input + " --json: no numeric field \"" + field + "\"";
      return build;
    }
  }
  stats["wall_seconds"] = build.run.wall_seconds;
  stats["child_peak_rss_mb"] = build.run.peak_rss_mb;
  stats["user_seconds"] = build.run.user_seconds;
  stats["system_seconds"] = build.run.system_seconds;
  build.stats = std::move(stats);
  return build;
}

// OpenMesh reads plain PLY/OBJ, so both tools get the same decompressed file.
fs::path decompress(const BenchContext& context, const fs::path& model) {
  const std::string extension = model.extension().string();
  const char* tool = extension == ".xz" ? "xz" : extension == ".gz" ? "gzip" : nullptr;
  if (!tool) return model;
  ChildOptions options = step_options();
  options.stdout_path = (context.temp_dir / model.stem()).string();
  const ChildResult run = run_child({tool, "-dc", model.string()}, options);
  if (!run.ok()) fail(model.string(), std::string(tool) + " -dc failed: " + run.failure());
  return options.stdout_path;
}

// "Bits for <tree-id, node-id>: <11, 17>" in mkbalancedpm's output.
std::string reported_bits(const std::string& output) {
  const std::string key = "Bits for <tree-id, node-id>: ";
  const size_t at = output.find(key);
  if (at == std::string::npos) return "";
  const size_t end = output.find('\n', at);
  return output.substr(at + key.size(), end == std::string::npos ? std::string::npos : end - at - key.size());
}

OpenMeshBuild run_openmesh(const std::string& label, const fs::path& mesh, const fs::path& work_stem) {
  OpenMeshBuild build;
  const std::string pm = work_stem.string() + ".pm", spm = work_stem.string() + ".spm";
  progress_begin(label + " " + kMkBalancedPm);
  build.mkbalancedpm = run_child({kMkBalancedPm, "-o", pm, mesh.string()}, step_options());
  progress_end(step_outcome(build.mkbalancedpm));
  if (!build.mkbalancedpm.ok()) {
    build.error = std::string(kMkBalancedPm) + ": " + build.mkbalancedpm.failure();
    return build;
  }
  build.reported_bits = reported_bits(build.mkbalancedpm.out + build.mkbalancedpm.err);
  try {
    build.pm = read_openmesh_pm(pm);
  } catch (const Error& e) {
    build.error = e.what();
    return build;
  }
  progress_begin(label + " " + kAnalyzer);
  build.analyzer = run_child({kAnalyzer, "-o", spm, pm}, step_options());
  progress_end(step_outcome(build.analyzer));
  if (!build.analyzer.ok()) build.error = std::string(kAnalyzer) + ": " + build.analyzer.failure();
  return build;
}

ModelResult run_model(const BenchContext& context, const std::string& name, const fs::path& file, bool openmesh,
                      const std::string& label) {
  ModelResult result{name, file, "", {}, std::nullopt, {}, {}};
  fs::path mesh;
  try {
    progress_begin(label + " decompress " + file.filename().string());
    const Stopwatch clock;
    mesh = decompress(context, file);
    progress_end(fixed(clock.seconds(), 2) + " s");
  } catch (const Error& e) {
    progress_end("FAILED");
    result.error = e.what();
    return result;
  }
  const fs::path work_stem = context.temp_dir / name;
  std::vector<OurBuild> ours;
  std::vector<OpenMeshBuild> theirs;
  for (size_t run = 0; run < runs(context); ++run) {
    const std::string step = label + (runs(context) > 1 ? " run " + std::to_string(run + 1) : "");
    progress_begin(step + " pmstream build");
    ours.push_back(run_our_build(context, mesh.string(), work_stem.string() + ".pms"));
    progress_end(ours.back().error.empty() ? step_outcome(ours.back().run) : "FAILED (" + ours.back().error + ")");
    if (openmesh) theirs.push_back(run_openmesh(step, mesh, work_stem));
    if (!ours.back().error.empty() || (openmesh && !theirs.back().error.empty())) {
      // Report the failure itself, not a median of what came before it.
      ours = {std::move(ours.back())};
      if (openmesh) theirs = {std::move(theirs.back())};
      break;
    }
  }
  for (const OurBuild& build : ours) result.ours_seconds.push_back(build.run.wall_seconds);
  for (const OpenMeshBuild& build : theirs) result.openmesh_seconds.push_back(openmesh_seconds(build));
  result.ours = median_run(ours, result.ours_seconds);
  if (openmesh) result.openmesh = median_run(theirs, result.openmesh_seconds);
  std::error_code ignored;  // scratch files can be large (the dragon's PLY, .pm and .spm): drop them now
  if (mesh != file) fs::remove(mesh, ignored);
  for (const char* extension : {".pms", ".pm", ".spm"}) fs::remove(work_stem.string() + extension, ignored);
  return result;
}

// ---------------------------------------------------------------------------------------------
// Tables and JSON

double number(const json& stats, const char* key) { return stats.at(key).get<double>(); }
uint64_t count(const json& stats, const char* key) { return stats.at(key).get<uint64_t>(); }

const PaperRow* paper_row(const std::string& model) {
  for (const PaperRow& row : kPaperTable1) {
    std::string a = row.model, b = model;
    std::transform(a.begin(), a.end(), a.begin(), ::tolower);
    std::transform(b.begin(), b.end(), b.begin(), ::tolower);
    if (a == b) return &row;
  }
  return nullptr;
}

Table e12_table() {
  return Table({{"model", false, 6},
                {"faces", true, 9},
                {"ours s", true, 6},
                {"ours build s", true, 0},
                {"ours peak MB", true, 0},
                {"ours .pms bytes", true, 0},
                {"mkbalancedpm s", true, 0},
                {"Analyzer s", true, 0},
                {"OpenMesh s", true, 0},
                {"OpenMesh peak MB", true, 0},
                {"speedup", true, 0},
                {"node-id bits ours", true, 0},
                {"node-id bits OpenMesh", true, 0}});
}

std::vector<std::string> e12_row(const ModelResult& r) {
  std::vector<std::string> cells(13);
  cells[0] = r.name;
  const json& s = r.ours.stats;
  if (!s.is_null()) {
    cells[1] = thousands(count(s, "input_faces"));
    cells[2] = fixed(r.ours.run.wall_seconds, 2);
    cells[3] = fixed(number(s, "build_seconds"), 2);
    cells[4] = fixed(number(s, "peak_rss_mb"), 0);
    cells[5] = thousands(count(s, "output_bytes"));
    cells[11] = std::to_string(count(s, "node_id_bits"));
  }
  if (r.openmesh && r.openmesh->error.empty()) {
    const OpenMeshBuild& om = *r.openmesh;
    const double total = openmesh_seconds(om);
    cells[6] = fixed(om.mkbalancedpm.wall_seconds, 2);
    cells[7] = fixed(om.analyzer.wall_seconds, 2);
    cells[8] = fixed(total, 2);
    cells[9] = fixed(std::max(om.mkbalancedpm.peak_rss_mb, om.analyzer.peak_rss_mb), 0);
    if (!s.is_null()) cells[10] = fixed(total / r.ours.run.wall_seconds, 2) + "×";
  }
  if (r.openmesh && r.openmesh->pm) cells[12] = std::to_string(r.openmesh->pm->max_depth);
  return cells;
}

Table e1_table() {
  return Table({{"model", false, 0},
                {"ours base #v", true, 0},
                {"ours #details", true, 0},
                {"ours <tree, node>", true, 0},
                {"OpenMesh base #v", true, 0},
                {"OpenMesh #details", true, 0},
                {"OpenMesh <tree, node>", true, 0},
                {"paper base #v", true, 0},
                {"paper #details", true, 0},
                {"paper <tree, node>", true, 0}});
}

void fill_paper_cells(std::vector<std::string>& cells, const PaperRow* paper) {
  if (!paper) {
    cells[7] = cells[8] = cells[9] = "not in paper";
    return;
  }
  cells[7] = thousands(paper->base_vertices);
  cells[8] = thousands(paper->details);
  cells[9] = id_bits(paper->tree_bits, paper->node_bits);
}

std::vector<std::string> e1_row(const ModelResult& r) {
  std::vector<std::string> cells(10);
  cells[0] = r.name;
  const json& s = r.ours.stats;
  if (!s.is_null()) {
    cells[1] = thousands(count(s, "base_vertices"));
    cells[2] = thousands(count(s, "vsplits"));
    cells[3] = id_bits(uint32_t(count(s, "tree_id_bits")), uint32_t(count(s, "node_id_bits")));
  }
  if (r.openmesh && r.openmesh->pm) {
    const OpenMeshPmStats& pm = *r.openmesh->pm;
    cells[4] = thousands(pm.base_vertices);
    if (pm.isolated_base_vertices > 0) cells[4] += " (" + thousands(pm.isolated_base_vertices) + " isolated)";
    cells[5] = thousands(pm.details);
    cells[6] = id_bits(pm.tree_id_bits, pm.max_depth);
  }
  fill_paper_cells(cells, paper_row(r.name));
  return cells;
}

bool have_model(const fs::path& models_dir, const std::string& name) {
  try {
    find_model(models_dir, name);
    return true;
  } catch (const Error&) {
    return false;
  }
}

// Paper models this run did not build, so Table 1 is always complete beside ours.
std::vector<std::string> e1_paper_only_row(const PaperRow& paper, bool have_mesh) {
  std::vector<std::string> cells(10, have_mesh ? "not run" : "not available");
  cells[0] = paper.model;
  fill_paper_cells(cells, &paper);
  return cells;
}

json child_json(const ChildResult& run) {
  return {{"wall_seconds", run.wall_seconds},
          {"user_seconds", run.user_seconds},
          {"system_seconds", run.system_seconds},
          {"peak_rss_mb", run.peak_rss_mb},
          {"ok", run.ok()},
          {"failure", run.failure()}};
}

json model_json(const ModelResult& r) {
  json j = {{"model", r.name}, {"file", r.file.string()}};
  if (!r.error.empty()) j["error"] = r.error;
  j["pmstream"] = r.ours.error.empty() ? r.ours.stats : json{{"error", r.ours.error}};
  j["pmstream_runs_seconds"] = r.ours_seconds;
  if (r.openmesh) {
    const OpenMeshBuild& om = *r.openmesh;
    // The analyzer runs only on a .pm that parsed.
    json o = {{"mkbalancedpm", child_json(om.mkbalancedpm)},
              {"analyzer", om.pm ? child_json(om.analyzer) : json(nullptr)}};
    if (!om.error.empty()) o["error"] = om.error;
    if (om.pm)
      o["pm"] = {{"base_vertices", om.pm->base_vertices},
                 {"isolated_base_vertices", om.pm->isolated_base_vertices},
                 {"base_faces", om.pm->base_faces},
                 {"details", om.pm->details},
                 {"tree_id_bits", om.pm->tree_id_bits},
                 {"node_id_bits", om.pm->max_depth},
                 {"mkbalancedpm_reported_bits", om.reported_bits}};
    o["runs_seconds"] = r.openmesh_seconds;
    if (om.error.empty() && !r.ours.stats.is_null()) o["speedup"] = openmesh_seconds(om) / r.ours.run.wall_seconds;
    j["openmesh"] = std::move(o);
  } else {
    j["openmesh"] = nullptr;
  }
  return j;
}

json paper_json() {
  json rows = json::array();
  for (const PaperRow& p : kPaperTable1)
    rows.push_back({{"model", p.model},
                    {"base_vertices", p.base_vertices},
                    {"details", p.details},
                    {"tree_id_bits", p.tree_bits},
                    {"node_id_bits", p.node_bits}});
  return rows;
}

// Facts read off the results, said next to the tables so nobody misreads them.
std::string model_notes(const std::vector<ModelResult>& results) {
  std::string notes;
  for (const ModelResult& r : results) {
    for (const std::string* error : {&r.error, &r.ours.error, r.openmesh ? &r.openmesh->error : nullptr})
      if (error && !error->empty()) notes += "- " + r.name + ": **failed**: " + *error + "\n";
    if (r.openmesh && r.openmesh->pm && r.openmesh->pm->isolated_base_vertices > 0)
      notes += "- " + r.name + ": OpenMesh keeps the " + thousands(r.openmesh->pm->isolated_base_vertices) +
               " input vertices that no face uses as extra base vertices (\"isolated\"); pmstream drops them "
               "while cleaning. This inflates OpenMesh's base #v and tree-id bits, as measured.\n";
    // The OpenMesh columns come from parsing the .pm; mkbalancedpm's own printout should agree.
    if (r.openmesh && r.openmesh->pm && !r.openmesh->reported_bits.empty() &&
        r.openmesh->reported_bits != id_bits(r.openmesh->pm->tree_id_bits, r.openmesh->pm->max_depth))
      notes += "- " + r.name + ": mkbalancedpm printed <tree-id, node-id> bits " + r.openmesh->reported_bits +
               ", the table shows what its .pm file holds.\n";
    const PaperRow* paper = paper_row(r.name);
    if (paper && !r.ours.stats.is_null()) {
      const uint64_t paper_vertices = uint64_t(paper->base_vertices) + paper->details;
      const uint64_t ours = count(r.ours.stats, "input_vertices");
      notes += "- " + r.name + ": the paper's mesh had " + thousands(paper_vertices) +
               " vertices (base + details), ours has " + thousands(ours) + " after cleaning" +
               (paper_vertices == ours ? ": the same vertex count.\n" : ": a different mesh, compare shapes only.\n");
    }
  }
  return notes;
}

// ---------------------------------------------------------------------------------------------
// The two parts of the group

std::string run_models(const BenchContext& context, json& out) {
  std::string section = "### E12 build cost and E1 hierarchy statistics (real models)\n\n";
  if (context.models_dir.empty()) {
    const std::string note =
        "../shared/models was not found (give --shared DIR or set PMSTREAM_SHARED_DIR): the real-model "
        "experiments E12 and E1 were skipped; the terrain series still runs.";
    std::fprintf(stderr, "bench: %s\n", note.c_str());
    out["models"] = json::array();
    return section + note + "\n\n";
  }
  const std::vector<std::string>& names = context.options.models.empty() ? kDefaultModels : context.options.models;
  std::vector<fs::path> files;
  for (const std::string& name : names) files.push_back(find_model(context.models_dir, name));

  const bool have_openmesh = !find_program(kMkBalancedPm).empty() && !find_program(kAnalyzer).empty();
  out["openmesh_tools"] =
      have_openmesh ? json{{"mkbalancedpm", find_program(kMkBalancedPm)}, {"analyzer", find_program(kAnalyzer)}}
                    : json(nullptr);
  if (!have_openmesh) {
    const std::string note = std::string(kMkBalancedPm) + " / " + kAnalyzer +
                             " not found (Debian package libopenmesh-apps): the OpenMesh columns are empty.";
    std::fprintf(stderr, "bench: %s\n", note.c_str());
    section += note + "\n\n";
  }

  Table e12 = e12_table();
  print("\nE12 build cost (" + context.models_dir.string() + ")\n\n" + e12.header());
  std::vector<ModelResult> results;
  out["models"] = json::array();
  for (size_t i = 0; i < names.size(); ++i) {
    const std::string label = "[" + names[i] + " " + std::to_string(i + 1) + "/" + std::to_string(names.size()) + "]";
    results.push_back(run_model(context, names[i], files[i], have_openmesh, label));
    print(e12.add_row(e12_row(results.back())));
    out["models"].push_back(model_json(results.back()));
  }

  Table e1 = e1_table();
  for (const ModelResult& r : results) e1.add_row(e1_row(r));
  for (const PaperRow& paper : kPaperTable1) {
    const bool run =
        std::any_of(results.begin(), results.end(), [&](const ModelResult& r) { return paper_row(r.name) == &paper; });
    if (!run) e1.add_row(e1_paper_only_row(paper, have_model(context.models_dir, paper.model)));
  }
  print("\nE1 hierarchy statistics beside kim-lee-kobbelt Table 1\n\n" + e1.markdown());
  out["paper_table1"] = paper_json();

  section +=
      "Each build runs as its own process on the same decompressed file; seconds are wall time and peak MB "
      "is the build's own (VmHWM, as `build --json` reports it; OpenMesh's tools: their ru_maxrss from wait4, "
      "which also counts pages inherited from the bench at fork), of the median of " +
      std::to_string(runs(context)) +
      " runs (ours and OpenMesh's in turn; every run's time is in build.json). \"ours s\" is the whole "
      "`pmstream build` (load, clean, build, write); \"ours build s\" excludes loading. OpenMesh s = mkbalancedpm + "
      "Analyzer (the analyzer adds "
      "the view-dependent refinement information, which our build includes). speedup = OpenMesh s / ours s.\n\n";
  section += e12.markdown() + "\n";
  section +=
      "E1: base #v, #details (vertex splits) and the bits of a <tree-id, node-id> (tree-id bits = "
      "ceil(log2 base #v), node-id bits = height of the hierarchy, the implicit leading 1 not counted).\n\n";
  section += e1.markdown() + "\n";
  const std::string notes = model_notes(results);
  if (!notes.empty()) section += notes + "\n";
  return section;
}

Table scaling_table() {
  return Table({{"faces", true, 10},
                {"seconds", true, 7},
                {"build s", true, 7},
                {"peak RSS MB", true, 0},
                {"µs/face", true, 0},
                {"(s/face) / (s/face)₀", true, 0},
                {"log2 n / log2 n₀", true, 0}});
}

// One terrain size: the median of runs(context) builds, or the first that failed (the failure itself, not
// a median of what came before it).
struct TerrainStep {
  std::string input;
  OurBuild build;
  std::vector<double> runs_seconds;
};

TerrainStep build_terrain(const BenchContext& context, size_t i, size_t steps) {
  TerrainStep step;
  step.input = "terrain:" + std::to_string(kTerrainFaces[i]);
  progress_begin("[" + step.input + " " + std::to_string(i + 1) + "/" + std::to_string(steps) +
                 "] pmstream build, median of " + std::to_string(runs(context)));
  const fs::path output = context.temp_dir / ("terrain-" + std::to_string(kTerrainFaces[i]) + ".pms");
  std::vector<OurBuild> all;
  for (size_t run = 0; run < runs(context); ++run) {
    all.push_back(run_our_build(context, step.input, output));
    step.runs_seconds.push_back(all.back().run.wall_seconds);
    if (!all.back().error.empty()) {
      all = {std::move(all.back())};
      step.runs_seconds = {step.runs_seconds.back()};
      break;
    }
  }
  step.build = median_run(all, step.runs_seconds);
  progress_end(step.build.error.empty() ? step_outcome(step.build.run) : "FAILED (" + step.build.error + ")");
  std::error_code ignored;
  fs::remove(output, ignored);
  return step;
}

// n₀, the first row that built: the others are read against it.
struct FirstRow {
  double faces = 0, seconds_per_face = 0;
};

std::vector<std::string> scaling_row(const OurBuild& build, const FirstRow& n0) {
  const double faces = double(count(build.stats, "input_faces"));
  const double seconds = build.run.wall_seconds;
  const double per_face = seconds / faces;
  return {thousands(uint64_t(faces)),
          fixed(seconds, 2),
          fixed(number(build.stats, "build_seconds"), 2),
          fixed(build.run.peak_rss_mb, 0),
          fixed(per_face * 1e6, 2),
          fixed(per_face / n0.seconds_per_face, 2),
          fixed(std::log2(faces) / std::log2(n0.faces), 2)};
}

std::string scaling_section(const BenchContext& context, const Table& table, const std::string& notes,
                            const Plot& plot) {
  std::string section = "### Scaling: procedural terrain\n\n";
  section += "`pmstream build terrain:FACES` in a child process, median of " + std::to_string(runs(context)) +
             " runs; seconds are wall time (terrain generation "
             "included, it is the \"load\"), \"build s\" excludes it. n₀ is the first row: the build grows no "
             "faster than n log n while (s/face) / (s/face)₀ stays at or below log2 n / log2 n₀.\n\n";
  section += table.markdown() + "\n";
  if (!notes.empty()) section += notes + "\n";
  const std::string skipped = plot_png(plot, context.options.out_dir / "scaling.png");
  if (skipped.empty()) {
    section += "![seconds and peak RSS vs faces](scaling.png)\n\n";
  } else {
    std::fprintf(stderr, "bench: %s\n", skipped.c_str());
    section += "No plot: " + skipped + ".\n\n";
  }
  return section;
}

std::string run_scaling(const BenchContext& context, json& out) {
  const size_t steps = context.options.quick ? kQuickTerrainSteps : kTerrainFaces.size();
  Table table = scaling_table();
  print("\nScaling: procedural terrain (pmstream build terrain:FACES)\n\n" + table.header());
  Plot plot{"pmstream build on the procedural terrain", "faces", "seconds", "peak RSS (MB)", true, true, {}};
  plot.series = {{"seconds (wall)", {}, {}, false}, {"peak RSS MB", {}, {}, true}};
  std::string notes;
  out["scaling"] = json::array();
  FirstRow n0;
  for (size_t i = 0; i < steps; ++i) {
    const TerrainStep step = build_terrain(context, i, steps);
    const OurBuild& build = step.build;
    out["scaling"].push_back({{"input", step.input},
                              {"pmstream", build.error.empty() ? build.stats : json{{"error", build.error}}},
                              {"runs_seconds", step.runs_seconds}});
    if (!build.error.empty()) {
      notes += "- " + step.input + ": **failed**: " + build.error + "\n";
      print(table.add_row({thousands(kTerrainFaces[i]), "", "", "", "", "", ""}));
      continue;
    }
    const double faces = double(count(build.stats, "input_faces"));
    if (n0.faces == 0) n0 = {faces, build.run.wall_seconds / faces};
    print(table.add_row(scaling_row(build, n0)));
    plot.series[0].x.push_back(faces);
    plot.series[0].y.push_back(build.run.wall_seconds);
    plot.series[1].x.push_back(faces);
    plot.series[1].y.push_back(build.run.peak_rss_mb);
  }
  return scaling_section(context, table, notes, plot);
}

}  // namespace

void run_build_group(BenchContext& context) {
  json out = {{"command", context.options.command_line},
              {"machine", machine_json()},
              {"models_dir", context.models_dir.empty() ? json(nullptr) : json(context.models_dir.string())}};
  std::string section = "## build: E12 build cost, E1 hierarchy statistics, scaling\n\n";
  section += run_models(context, out);
  section += run_scaling(context, out);
  // Tools' stderr lines end up in the JSON: replace bytes that are not UTF-8 instead of throwing.
  write_text_file(context.options.out_dir / "build.json",
                  out.dump(2, ' ', false, json::error_handler_t::replace) + "\n");
  context.report += section;
}

}  // namespace pms::bench
