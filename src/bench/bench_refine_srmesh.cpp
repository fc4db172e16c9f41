// The refine group's comparison with Hoppe's SrMesh (issue 18): bunny at four camera distances, faces at
// τ = 1 px and the cost of a steady frame, an orbit step and the refinement from the base mesh (on a mesh
// whose memory was used before, and on a fresh one), beside the figures Hoppe's own code gave on this
// machine type; the same timings on dragon. docs/architecture.md ("Bench figures") says what each means.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>

#include "apps/percentile.h"
#include "apps/resource_usage.h"
#include "bench/bench_model.h"
#include "bench/bench_refine.h"
#include "bench/report.h"
#include "common/error.h"
#include "spm/adapt.h"
#include "spm/selective_mesh.h"

namespace pms::bench {
using app::percentile;
using app::Stopwatch;
using nlohmann::json;
namespace {

// Hugues Hoppe's Mesh-processing-library (commit a288d07: `MeshSimplify -vsgeom`, then `SrMesh`) on the
// bunny as pmstream cleans it, measured on this machine type with these cameras (issue 18).
struct SrMeshRow {
  float distance;
  uint32_t faces;
  double steady_ms, orbit_ms, from_base_ms;
};
constexpr SrMeshRow kSrMeshBunny[] = {{1.5f, 9913, 0.088, 0.103, 1.06},
                                      {3, 5439, 0.035, 0.038, 0.47},
                                      {10, 1525, 0.011, 0.010, 0.13},
                                      {50, 213, 0.001, 0.001, 0.021}};

constexpr float kTolerance = 1;
constexpr float kCoarsenTolerance = 1e9f;  // no node's error is that visible: converging goes back to the base
constexpr float kOrbitStepDeg = 0.25f;
constexpr uint32_t kOrbitSteps = 20;   // 0° → 5°, then back
constexpr uint32_t kSteadyBatch = 20;  // adapts per steady sample: one is too short for the clock

struct DistanceRun {
  float distance = 0;
  uint64_t faces = 0;
  std::vector<double> steady_ms, unchanged_ms, orbit_ms, base_ms, fresh_ms;  // one sample per repeat
  uint32_t steady_evaluated = 0;
  double orbit_evaluated = 0, orbit_ops = 0;  // per step
  uint32_t base_splits = 0, base_evaluated = 0;
};

AdaptOptions tolerance(float tau) { return AdaptOptions{tau, 0, 0}; }

void coarsen(SelectiveRefinement& refinement, const ModelData& model) {
  refinement.set_options(tolerance(kCoarsenTolerance));
  refinement.converge();
  refinement.set_options(tolerance(kTolerance));
  if (refinement.mesh().face_count() != model.base_faces.size() / 3)
    fail("bench refine", "coarsening did not reach the base");
}

// From the base mesh to the view's target in one adapt (every split is known, so the split-only walk
// reaches it); the next frame must find nothing to do.
FrameStats timed_from_base(SelectiveRefinement& refinement, const ViewParams& view, std::vector<double>& ms) {
  Stopwatch clock;
  refinement.set_view(view);
  const FrameStats stats = refinement.adapt();
  ms.push_back(1000 * clock.seconds());
  if (refinement.adapt().ops() != 0) fail("bench refine", "refining from the base took more than one frame");
  return stats;
}

// A fresh mesh and refinement over the loaded hierarchy, timed from construction to the view's target:
// what a viewer pays for its first picture once the model is in memory.
void time_fresh(const ModelData& model, const VertexHierarchy& h, const ViewParams& view, std::vector<double>& ms) {
  Stopwatch clock;
  auto mesh = std::make_unique<SelectiveMesh>(h, model.base_faces);
  auto refinement = std::make_unique<SelectiveRefinement>(*mesh, model.scale, tolerance(kTolerance));
  refinement->set_view(view);
  refinement->adapt();
  ms.push_back(1000 * clock.seconds());
}

// Every split in PM order: the mesh's memory has held the full model, as in Hoppe's driver.
void refine_fully(SelectiveMesh& mesh, const ModelData& model, const VertexHierarchy& h) {
  for (uint32_t node : model.split_order) mesh.vsplit(h.find(model.id(node)));
}

DistanceRun run_distance(const ModelData& model, const VertexHierarchy& h, float distance, uint32_t repeats) {
  DistanceRun run;
  run.distance = distance;
  const ViewParams view = make_view(srmesh_camera(model, distance, 0), model.bbox_min, model.bbox_max);
  SelectiveMesh mesh(h, model.base_faces);
  SelectiveRefinement refinement(mesh, model.scale, tolerance(kTolerance));
  refinement.set_view(view);
  refine_fully(mesh, model, h);
  // One untimed frame from the base first: it decodes the view's slots, the refinement's own memory,
  // which SrMesh fills when it loads a model. What that first decode costs is the fresh column's.
  std::vector<double> untimed;
  coarsen(refinement, model);
  timed_from_base(refinement, view, untimed);
  for (uint32_t i = 0; i < repeats; ++i) {
    coarsen(refinement, model);
    const FrameStats stats = timed_from_base(refinement, view, run.base_ms);
    run.base_splits = stats.vsplits;
    run.base_evaluated = stats.evaluated;
  }
  run.faces = mesh.face_count();
  for (uint32_t i = 0; i < repeats; ++i) {
    Stopwatch clock;
    for (uint32_t k = 0; k < kSteadyBatch; ++k) {
      refinement.rewalk();  // the walk Hoppe's steady frame does; unchanged_ms below is what a viewer pays
      run.steady_evaluated = refinement.adapt().evaluated;
    }
    run.steady_ms.push_back(1000 * clock.seconds() / kSteadyBatch);
    Stopwatch unchanged;
    for (uint32_t k = 0; k < kSteadyBatch; ++k) refinement.adapt();
    run.unchanged_ms.push_back(1000 * unchanged.seconds() / kSteadyBatch);
  }
  uint64_t evaluated = 0, ops = 0;
  for (uint32_t i = 0; i < repeats; ++i) {
    double seconds = 0;
    for (uint32_t step = 1; step <= 2 * kOrbitSteps; ++step) {
      const uint32_t at = step <= kOrbitSteps ? step : 2 * kOrbitSteps - step;
      const ViewParams turned =
          make_view(srmesh_camera(model, distance, float(at) * kOrbitStepDeg), model.bbox_min, model.bbox_max);
      Stopwatch clock;
      refinement.set_view(turned);
      const FrameStats stats = refinement.adapt();
      seconds += clock.seconds();
      evaluated += stats.evaluated;
      ops += stats.ops();
    }
    run.orbit_ms.push_back(1000 * seconds / (2 * kOrbitSteps));
  }
  run.orbit_evaluated = double(evaluated) / (repeats * 2 * kOrbitSteps);
  run.orbit_ops = double(ops) / (repeats * 2 * kOrbitSteps);
  for (uint32_t i = 0; i < repeats; ++i) time_fresh(model, h, view, run.fresh_ms);
  return run;
}

double median(const std::vector<double>& v) { return percentile(v, 0.5); }

std::string ms_text(double ms) {
  char text[32];
  std::snprintf(text, sizeof text, ms >= 1 ? "%.2f" : "%.3g", ms);
  return text;
}

// The samples' range, fastest–slowest: this shared VM slows in phases, so a median of few samples moves
// between runs of the same binary and the fastest is the steadiest figure to compare.
std::string spread_text(const std::vector<double>& samples) {
  const auto [fastest, slowest] = std::minmax_element(samples.begin(), samples.end());
  return samples.empty() ? "n/a" : ms_text(*fastest) + "–" + ms_text(*slowest);
}

Table spread_table(const std::vector<DistanceRun>& runs) {
  Table table({{"d", true}, {"steady ms", true}, {"orbit ms", true}, {"from base ms", true}, {"fresh ms", true}});
  for (const DistanceRun& run : runs)
    table.add_row({fixed(run.distance, 1), spread_text(run.steady_ms), spread_text(run.orbit_ms),
                   spread_text(run.base_ms), spread_text(run.fresh_ms)});
  return table;
}

// The first fresh sample of a run is the process's first mesh whose arrays are new memory (the other
// meshes alive hold the recycled blocks): what a viewer opening a model pays, page faults included.
std::string cold_line(const std::vector<DistanceRun>& runs) {
  if (runs.empty() || runs[0].fresh_ms.empty()) return "";
  return "The first fresh mesh of the run (d = " + fixed(runs[0].distance, 1) + ") took " +
         ms_text(runs[0].fresh_ms[0]) +
         " ms: its arrays were memory new to the process (page faults); the other fresh samples reuse a freed mesh's "
         "pages.\n";
}

std::string base_cell(const DistanceRun& run) {
  return ms_text(median(run.base_ms)) + " (" + ms_text(median(run.fresh_ms)) + " fresh)";
}

json run_json(const DistanceRun& run) {
  return {{"distance", run.distance},
          {"faces", run.faces},
          {"steady_ms", run.steady_ms},
          {"unchanged_ms", run.unchanged_ms},
          {"orbit_ms", run.orbit_ms},
          {"from_base_ms", run.base_ms},
          {"fresh_ms", run.fresh_ms},
          {"steady_evaluated", run.steady_evaluated},
          {"orbit_evaluated_per_step", run.orbit_evaluated},
          {"orbit_ops_per_step", run.orbit_ops},
          {"from_base_splits", run.base_splits},
          {"from_base_evaluated", run.base_evaluated}};
}

std::vector<DistanceRun> run_model(const ModelData& model, const std::string& name, uint32_t repeats) {
  std::fprintf(stderr, "bench: %s at %zu distances, %u repeats ...\n", name.c_str(), std::size(kSrMeshBunny), repeats);
  const VertexHierarchy h = complete_hierarchy(model);
  std::vector<DistanceRun> runs;
  for (const SrMeshRow& row : kSrMeshBunny) runs.push_back(run_distance(model, h, row.distance, repeats));
  return runs;
}

// The work behind the timings: qrefine evaluations and operations (counts do not depend on the load).
Table counts_table(const std::vector<DistanceRun>& runs) {
  Table table({{"d", true},
               {"steady evaluated", true},
               {"unchanged frame ms", true},
               {"orbit evaluated/step", true},
               {"orbit ops/step", true},
               {"from base splits", true},
               {"from base evaluated", true}});
  for (const DistanceRun& run : runs)
    table.add_row({fixed(run.distance, 1), thousands(run.steady_evaluated), ms_text(median(run.unchanged_ms)),
                   fixed(run.orbit_evaluated, 0), fixed(run.orbit_ops, 1), thousands(run.base_splits),
                   thousands(run.base_evaluated)});
  return table;
}

}  // namespace

// eye = c + d·r·(sin a, 0, cos a), c the box centre and r half its diagonal, looking at c, up +y.
Camera srmesh_camera(const ModelData& model, float distance, float angle_deg) {
  float centre[3], diagonal2 = 0;
  for (int k = 0; k < 3; ++k) {
    centre[k] = 0.5f * (model.bbox_min[k] + model.bbox_max[k]);
    const float extent = model.bbox_max[k] - model.bbox_min[k];
    diagonal2 += extent * extent;
  }
  const float reach = distance * 0.5f * std::sqrt(diagonal2), angle = angle_deg * float(M_PI) / 180;
  Camera camera;
  for (int k = 0; k < 3; ++k) camera.target[k] = centre[k];
  camera.eye[0] = centre[0] + reach * std::sin(angle);
  camera.eye[1] = centre[1];
  camera.eye[2] = centre[2] + reach * std::cos(angle);
  camera.fovy_deg = 60;
  camera.width = 1920;
  camera.height = 1080;
  return camera;
}

std::string srmesh_comparison_section(const BenchContext& context, json& out) {
  const uint32_t repeats = context.options.quick ? 3 : 9;
  const BenchModel bunny = prepare_model(context, "bunny");
  const std::vector<DistanceRun> bunny_runs = run_model(bunny.served->model(), "bunny", repeats);
  Table table({{"d", true},
               {"faces Hoppe", true},
               {"faces pmstream", true},
               {"steady ms Hoppe", true},
               {"pmstream", true},
               {"orbit ms Hoppe", true},
               {"pmstream", true},
               {"from base ms Hoppe", true},
               {"pmstream", true}});
  for (size_t i = 0; i < bunny_runs.size(); ++i) {
    const SrMeshRow& hoppe = kSrMeshBunny[i];
    const DistanceRun& run = bunny_runs[i];
    table.add_row({fixed(run.distance, 1), thousands(hoppe.faces), thousands(run.faces), ms_text(hoppe.steady_ms),
                   ms_text(median(run.steady_ms)), ms_text(hoppe.orbit_ms), ms_text(median(run.orbit_ms)),
                   ms_text(hoppe.from_base_ms), base_cell(run)});
  }
  const Table bunny_counts = counts_table(bunny_runs);
  const Table bunny_spread = spread_table(bunny_runs);
  json& o = out["srmesh"];
  for (const DistanceRun& run : bunny_runs) o["bunny"].push_back(run_json(run));
  std::string section = "### Against Hoppe's SrMesh, bunny, τ = 1 px, 1920×1080, 60° (median of " +
                        std::to_string(repeats) +
                        " runs; Hoppe's columns measured with his code on this machine type)\n\n" + table.markdown() +
                        "\nThe spread of those runs (fastest–slowest):\n\n" + bunny_spread.markdown() + "\n" +
                        cold_line(bunny_runs) + "\nThe work behind it:\n\n" + bunny_counts.markdown() + "\n";
  print_now(
      "\nAgainst Hoppe's SrMesh, bunny (targets: faces, steady, orbit, from base ≤ Hoppe's; fresh ≤ 1.5× Hoppe's from "
      "base)\n" +
      table.markdown() + bunny_spread.markdown() + cold_line(bunny_runs) + bunny_counts.markdown());

  if (context.options.quick) return section;
  const BenchModel dragon = prepare_model(context, "dragon");
  const std::vector<DistanceRun> dragon_runs = run_model(dragon.served->model(), "dragon", repeats);
  Table dragon_table({{"d", true}, {"faces", true}, {"steady ms", true}, {"orbit ms", true}, {"from base ms", true}});
  for (const DistanceRun& run : dragon_runs) {
    dragon_table.add_row({fixed(run.distance, 1), thousands(run.faces), ms_text(median(run.steady_ms)),
                          ms_text(median(run.orbit_ms)), base_cell(run)});
    o["dragon"].push_back(run_json(run));
  }
  const Table dragon_counts = counts_table(dragon_runs);
  print_now("\nThe same cameras on dragon\n" + dragon_table.markdown() + dragon_counts.markdown());
  return section + "### The same cameras on dragon\n\n" + dragon_table.markdown() + "\n" + dragon_counts.markdown() +
         "\n";
}

}  // namespace pms::bench
