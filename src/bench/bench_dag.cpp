// The "dag" group, E9 (zheng-chan 2006 §6, Figs. 6–9): dragon along the paper's two routes (route 1: 180
// frames scanning bottom to top; route 2: 194 frames circling in close, faster and faster), τ = 0.1 % of
// the viewport height, N = 300, a 60,000-triangle budget. Per route and traversal (priority, linear,
// constant-time, and priority under the client's FREE/BUDGET management): the time of MANAGE-TRAVERSAL per
// frame, the accuracy of linear and constant-time against priority (the share of priority's triangles their
// mesh also has, every 5 frames), the fronts against the mesh, the server's state per session and the bytes
// down per frame. Fig. 8: the three traversals' meshes rendered at frame 110 of route 1. Then N chosen from
// the frame time left against fixed N (dag_frame_budget.h).
//
// Each traversal runs twice in lockstep on the same views: once as the real DAG mode (a server Session in this
// process, a StreamingClient applying its DAG_OPS, for bytes, session state and the client's mesh), once as a
// bare DagTraverser over its own cut, timed alone: as the session does, each frame loads the compact cut into
// the thread's dense one, traverses, and stores it back (the load and the store timed apart from the
// traversal). Both are deterministic, so the two cuts must agree; the bench fails if they do not.
#include <algorithm>
#include <array>
#include <cstdio>

#include "apps/camera_path.h"
#include "apps/percentile.h"
#include "apps/resource_usage.h"
#include "bench/bench.h"
#include "bench/bench_model.h"
#include "bench/bench_refine.h"
#include "bench/gnuplot.h"
#include "bench/dag_frame_budget.h"
#include "bench/mesh_faces.h"
#include "bench/report.h"
#include "client/streaming_client.h"
#include "common/error.h"
#include "dag/compact.h"
#include "dag/traversal.h"
#include "protocol/client_messages.h"
#include "render/render.h"
#include "server/dag_mode.h"
#include "server/session_mode.h"

namespace pms::bench {
using app::PathKind;
using app::percentile;
using app::Stopwatch;
namespace {

using nlohmann::json;

constexpr uint32_t kRoute1Frames = 180, kRoute2Frames = 194, kQuickFrames = 40;
constexpr uint32_t kFigureFrame = 110;  // Fig. 8, of route 1's 180 (scaled to a quick run's frames)
constexpr uint32_t kMaxOps = 300;
constexpr uint64_t kBudget = 60000;
constexpr float kToleranceOfHeight = 0.001f;
constexpr uint32_t kAccuracyEvery = 5;

// The last is priority again, FREE or BUDGET as the client's management picks (--management auto).
constexpr int kRuns = 4, kTraversalsDrawn = 3;
constexpr DagTraversal kTraversals[] = {DagTraversal::priority, DagTraversal::linear, DagTraversal::constant_time,
                                        DagTraversal::priority};
constexpr const char* kTraversalNames[] = {"priority", "linear", "constant-time", "priority, management auto"};
constexpr const char* kFileNames[] = {"priority", "linear", "constant-time", "priority-auto"};

struct TraversalRun {
  struct First {
    double ms = 0, evaluated = 0, ops = 0, down_bytes = 0;
  } first;                                                   // the first view's converged answer
  std::vector<double> frame_ms, evaluated, ops, down_bytes;  // frames 1..
  std::vector<double> load_ms, store_ms;                     // frames 1..: the compact cut to dense and back
  std::vector<double> triangles, front_share;                // every frame
  size_t max_session_bytes = 0, max_cut_bytes = 0, max_scratch_bytes = 0;
  uint64_t max_triangles = 0;
  std::vector<std::vector<IdFace>> samples;  // the client's mesh every kAccuracyEvery frames
  MeshArrays figure;                         // the client's mesh at the figure's frame
  uint32_t free_requests = 0;                // DAG_VIEWs the client sent in FREE mode
  std::vector<double> accuracy;              // against priority's samples: the share of priority's triangles it has
  std::vector<double> precision;             // the share of its own triangles that priority's mesh has
};

const server::DagSessionMode& dag_mode_of(const InProcessSession& local) {
  return dynamic_cast<const server::DagSessionMode&>(*local.session->session_mode());
}

TraversalRun run_traversal(const BenchModel& m, const std::vector<Camera>& route, DagTraversal traversal,
                           bool management_auto, uint32_t figure_frame) {
  const float tolerance = kToleranceOfHeight * float(route[0].height);
  InProcessSession local = in_process_session(m);
  client::ClientOptions options{tolerance};
  options.mode = protocol::StreamMode::dag;
  options.dag.traversal = traversal;
  options.dag.management = DagMode::budget;
  options.dag.budget = kBudget;
  options.dag.max_ops = kMaxOps;
  options.dag_management.automatic = management_auto;
  client::StreamingClient client(std::move(local.transport), options);
  client.open(m.name);

  const Dag& dag = m.served->tables->dag();
  CompactDagCut compact;
  const DagManageOptions manage{traversal, DagMode::budget, kMaxOps, kBudget};
  server::LatestView view;
  std::vector<DagOp> ops;
  TraversalRun run;
  for (uint32_t i = 0; i < route.size(); ++i) {
    view.record({route[i], tolerance, i + 1}, m.served->model());
    ops.clear();
    Stopwatch load_clock;
    LoadedDagCut loaded(dag, compact);
    const double load_ms = 1000 * load_clock.seconds();
    DagCut& cut = loaded.cut();
    DagTraverser traverser(cut);
    Stopwatch clock;
    traverser.set_view(view.criteria);
    // As the DAG mode answers a session's first view: converged (docs/internals.md, "The DAG mode").
    const DagFrameStats stats =
        i == 0 ? traverser.converge(manage, ops, protocol::kMaxDagOps) : traverser.manage(manage, ops);
    const double ms = 1000 * clock.seconds();
    const uint64_t triangles = cut.triangles();
    const double front_share = double(cut.fc_size() + cut.fs_size()) / double(std::max<uint64_t>(triangles, 1));
    Stopwatch store_clock;
    compact = loaded.store();  // and the dense cut back to the base mesh
    const double store_ms = 1000 * store_clock.seconds();

    const client::FrameReport report = client.frame(route[i]);
    run.free_requests += client.last_dag_request().management == DagMode::free;
    if (i == figure_frame) client.session().mesh().extract(run.figure);
    const server::DagSessionMode& mode = dag_mode_of(local);
    if (mode.cut().split_count() != compact.split_count() || mode.cut().triangles() != triangles ||
        client.session().mesh().face_count() != triangles)
      fail("bench dag",
           "frame " + std::to_string(i) + ": the session's cut or the client's mesh is not the traverser's");
    if (i == 0) {
      run.first = {ms, double(stats.evaluated), double(ops.size()), double(report.down_bytes)};
    } else {
      run.frame_ms.push_back(ms);
      run.load_ms.push_back(load_ms);
      run.store_ms.push_back(store_ms);
      run.evaluated.push_back(stats.evaluated);
      run.ops.push_back(double(ops.size()));
      run.down_bytes.push_back(double(report.down_bytes));
    }
    run.triangles.push_back(double(triangles));
    run.front_share.push_back(front_share);
    run.max_triangles = std::max(run.max_triangles, triangles);
    run.max_session_bytes = std::max(run.max_session_bytes, mode.state_bytes());
    run.max_cut_bytes = std::max(run.max_cut_bytes, compact.memory_bytes());
    run.max_scratch_bytes =
        std::max(run.max_scratch_bytes, DagTraverser::thread_scratch_bytes() + LoadedDagCut::thread_scratch_bytes());
    if (i % kAccuracyEvery == 0) run.samples.push_back(faces_by_id(client.session().mesh()));
  }
  return run;
}

double mean(const std::vector<double>& v) {
  double sum = 0;
  for (double x : v) sum += x;
  return v.empty() ? 0 : sum / double(v.size());
}

std::vector<double> sample_frames(size_t count) {
  std::vector<double> frames;
  for (size_t k = 0; k < count; ++k) frames.push_back(double(k * kAccuracyEvery));
  return frames;
}

std::vector<double> all_frames(size_t count, size_t first = 0) {
  std::vector<double> frames;
  for (size_t k = first; k < first + count; ++k) frames.push_back(double(k));
  return frames;
}

std::string plots(const BenchContext& context, const std::string& prefix, const std::string& route,
                  const TraversalRun (&runs)[kRuns]) {
  Plot time{"DAG traversal time per frame, " + route, "frame", "ms (log)", "", false, true, {}};
  Plot accuracy{"Correct triangles against priority, every 5 frames, " + route, "frame", "% of priority's triangles",
                "", false, false, {}};
  Plot fronts{"Fronts against the mesh, " + route, "frame", "(Fc + Fs) / triangles", "triangles", false, false, {}};
  for (int t = 0; t < kTraversalsDrawn; ++t) {
    const std::vector<double> frames = all_frames(runs[t].triangles.size());
    time.series.push_back({kTraversalNames[t], all_frames(runs[t].frame_ms.size(), 1), runs[t].frame_ms});
    if (t > 0)
      accuracy.series.push_back({kTraversalNames[t], sample_frames(runs[t].accuracy.size()), runs[t].accuracy});
    fronts.series.push_back({kTraversalNames[t], frames, runs[t].front_share});
    fronts.series.push_back({std::string(kTraversalNames[t]) + " triangles", frames, runs[t].triangles, true});
  }
  const std::filesystem::path& dir = context.options.out_dir;
  return plot_markdown(dir, time, prefix + "-time.png", "traversal ms per frame, " + route) +
         plot_markdown(dir, accuracy, prefix + "-accuracy.png", "accuracy against priority, " + route) +
         plot_markdown(dir, fronts, prefix + "-fronts.png", "front size against mesh size, " + route);
}

// Fig. 8: each traversal's mesh at the figure's frame, as the client holds it, rendered from that frame's
// camera, side by side in the report.
std::string figure_8(const BenchContext& context, const BenchModel& m, const Camera& camera, uint32_t frame,
                     const TraversalRun (&runs)[kRuns]) {
  const ModelData& model = m.served->model();
  const ViewParams view = make_view(camera, model.bbox_min, model.bbox_max);
  Renderer renderer;
  Image image;
  std::string header = "|", rule = "|", cells = "|";
  for (int t = 0; t < kTraversalsDrawn; ++t) {
    const MeshArrays& mesh = runs[t].figure;
    renderer.render({mesh.positions, mesh.indices, mesh.colors}, view, image);
    const std::string png = std::string("dag-fig8-") + kFileNames[t] + ".png";
    save_png((context.options.out_dir / png).string(), image);
    header += " (" + std::string(1, char('a' + t)) + ") " + kTraversalNames[t] + ", " +
              thousands(mesh.indices.size() / 3) + " triangles |";
    rule += " --- |";
    cells += " ![" + std::string(kTraversalNames[t]) + "](" + png + ") |";
  }
  return "### Fig. 8: the three traversals' meshes at frame " + std::to_string(frame) + " of route 1\n\n" + header +
         "\n" + rule + "\n" + cells +
         "\n\nThe client's mesh after the frame, rendered by the bench's software renderer from the frame's camera "
         "(the paper's Fig. 8 shows Buddha; ours is the model above).\n\n";
}

json run_json(const TraversalRun& run, uint32_t nodes) {
  return {{"first_view",
           {{"ms", run.first.ms},
            {"evaluated", run.first.evaluated},
            {"ops", run.first.ops},
            {"down_bytes", run.first.down_bytes}}},
          {"frame_ms", run.frame_ms},
          {"load_ms", run.load_ms},
          {"store_ms", run.store_ms},
          {"evaluated", run.evaluated},
          {"ops", run.ops},
          {"down_bytes", run.down_bytes},
          {"triangles", run.triangles},
          {"front_share", run.front_share},
          {"accuracy_every_5_frames", run.accuracy},
          {"precision_every_5_frames", run.precision},
          {"max_session_bytes", run.max_session_bytes},
          {"max_cut_bytes", run.max_cut_bytes},
          {"max_thread_scratch_bytes", run.max_scratch_bytes},
          {"session_bytes_per_node", double(run.max_session_bytes) / nodes}};
}


struct RouteRuns {
  std::string section;
  TraversalRun runs[kRuns];
};

// Every traversal along one route: its table and plots, and its JSON under out[route.name].
RouteRuns route_traversals(const BenchContext& context, const BenchModel& m, const DagRoute& route,
                           uint32_t figure_frame, json& out) {
  const uint32_t nodes = m.served->tables->dag().size();
  const float tolerance = kToleranceOfHeight * float(route.cameras[0].height);
  RouteRuns r;
  TraversalRun(&runs)[kRuns] = r.runs;
  for (int t = 0; t < kRuns; ++t) {
    std::fprintf(stderr, "bench: dag %s, %s ...\n", route.name.c_str(), kTraversalNames[t]);
    runs[t] = run_traversal(m, route.cameras, kTraversals[t], t == kRuns - 1, figure_frame);
  }
  for (TraversalRun& run : runs)
    for (size_t k = 0; k < run.samples.size(); ++k) {
      run.accuracy.push_back(shared_percent(run.samples[k], runs[0].samples[k]));
      run.precision.push_back(shared_percent(runs[0].samples[k], run.samples[k]));
    }
  // Frame 0 is every traversal's converged first view, the same mesh: left out of the average.
  const auto route_mean = [](const std::vector<double>& samples) {
    return mean(
        std::vector<double>(samples.begin() + std::min<ptrdiff_t>(1, ptrdiff_t(samples.size())), samples.end()));
  };

  Table table({{"traversal", false},
               {"first view ms", true},
               {"first view ops", true},
               {"median ms", true},
               {"p99 ms", true},
               {"load + store ms", true},
               {"evaluated / frame", true},
               {"ops / frame", true},
               {"max triangles", true},
               {"(Fc + Fs) / triangles", true},
               {"accuracy %", true},
               {"precision %", true},
               {"FREE requests %", true},
               {"session B / node", true},
               {"session KB", true},
               {"cut KB", true},
               {"thread scratch KB", true},
               {"bytes down / frame", true}});
  json route_json = {{"label", route.label}, {"frames", route.cameras.size()}};
  for (int t = 0; t < kRuns; ++t) {
    const TraversalRun& run = runs[t];
    table.add_row({kTraversalNames[t], fixed(run.first.ms, 1), thousands(uint64_t(run.first.ops)),
                   fixed(percentile(run.frame_ms, 0.5), 3), fixed(percentile(run.frame_ms, 0.99), 3),
                   fixed(percentile(run.load_ms, 0.5), 3) + " + " + fixed(percentile(run.store_ms, 0.5), 3),
                   thousands(uint64_t(mean(run.evaluated))), thousands(uint64_t(mean(run.ops))),
                   thousands(run.max_triangles), fixed(percentile(run.front_share, 0.5), 2),
                   t == 0 ? "—" : fixed(route_mean(run.accuracy), 1),
                   t == 0 ? "—" : fixed(route_mean(run.precision), 1),
                   fixed(100.0 * run.free_requests / double(route.cameras.size()), 1),
                   fixed(double(run.max_session_bytes) / nodes, 3), fixed(double(run.max_session_bytes) / 1e3, 1),
                   fixed(double(run.max_cut_bytes) / 1e3, 1), fixed(double(run.max_scratch_bytes) / 1e3, 1),
                   thousands(uint64_t(mean(run.down_bytes)))});
    route_json[kFileNames[t]] = run_json(run, nodes);
    route_json[kFileNames[t]]["free_requests"] = run.free_requests;
  }
  out[route.name] = route_json;
  const std::string settings = m.name + ", " + route.label + ", τ = " + fixed(tolerance, 3) +
                               " px (0.1 % of the height), N = " + std::to_string(kMaxOps) + ", BUDGET " +
                               thousands(kBudget) + " triangles, " + thousands(nodes) + " DAG nodes";
  print_now("\nE9: DAG traversals, " + route.name + ", " + settings +
            " (targets: constant-time ≤ 0.1 ms, priority ≤ 2 ms median; accuracy linear ≥ 80 %, constant-time ≥ 70 %; "
            "session ≤ 0.1 B / node)\n" +
            table.markdown());
  std::string prefix = "dag-" + route.name;
  std::replace(prefix.begin(), prefix.end(), ' ', '-');
  r.section = "### Traversals along " + route.name + " (" + settings + ")\n\n" + table.markdown() + "\n" +
              plots(context, prefix, route.name, runs);
  return r;
}

const char* const kTraversalNotes =
    "First view: the converged answer to the session's first view (the same for every traversal). ms: "
    "MANAGE-TRAVERSAL alone on a bare cut, fed the same views as the session, frames 1 on; load + store: the "
    "medians of decoding the compact cut into the thread's dense one and encoding it back (each turn of a session "
    "does both). Accuracy: the share of priority's triangles (by vertex ids) the client's mesh also has, every 5 "
    "frames from frame 5, averaged; precision: the share of the client's own triangles that priority's mesh has, "
    "averaged alike. FREE requests: the DAG_VIEWs the client sent in FREE mode; \"priority, management auto\" is "
    "the client choosing FREE or BUDGET by the paper's rule (`--management auto`: FREE while its mesh plus 2 N "
    "fits the budget), the others BUDGET throughout. Its mesh is priority's every frame (accuracy 100 %): our "
    "server's BUDGET mode counts the cut's own triangles, so in a frame the rule sends in FREE mode the budget "
    "could not have stopped a split; the rule spares the server the budget, not the client triangles. Session: "
    "the DAG mode's `state_bytes()` at its largest along the route; cut: `CompactDagCut::memory_bytes()` (what a "
    "session keeps between turns); thread scratch: the dense cut and the traversals' heaps and stack one I/O "
    "thread keeps (shared by the sessions of a thread, not per session), run so far. Bytes down: DAG_OPS frames "
    "as received, mean per frame. docs/internals.md, \"E9\", says what each figure is.\n\n";

}  // namespace

void run_dag_group(BenchContext& context) {
  std::string section = "## dag: E9, the DAG of operations' traversals (zheng-chan 2006 §6)\n\n";
  if (skipped_without_models(context, section)) return;
  const bool quick = context.options.quick;
  const std::string name = context.options.models.empty() ? (quick ? "bunny" : "dragon") : context.options.models[0];
  const BenchModel m = prepare_model(context, name);
  const uint32_t frames1 = quick ? kQuickFrames : kRoute1Frames, frames2 = quick ? kQuickFrames : kRoute2Frames;
  const std::vector<DagRoute> routes = {
      {"route 1", std::to_string(frames1) + "-frame scan, bottom to top", path_of(m, PathKind::scan, frames1)},
      {"route 2", std::to_string(frames2) + "-frame rotation in close, faster and faster",
       path_of(m, PathKind::rotate, frames2)}};
  const uint32_t figure_frame = kFigureFrame * frames1 / kRoute1Frames;

  json out = {{"command", context.options.command_line},
              {"machine", machine_json()},
              {"model", name},
              {"nodes", m.served->tables->dag().size()},
              {"max_ops", kMaxOps},
              {"budget", kBudget},
              {"figure_frame", figure_frame},
              {"dag_bytes", m.served->tables->dag().memory_bytes()}};
  std::string figure;
  for (size_t r = 0; r < routes.size(); ++r) {
    const RouteRuns runs = route_traversals(context, m, routes[r], r == 0 ? figure_frame : UINT32_MAX, out);
    section += runs.section;
    if (r == 0) figure = figure_8(context, m, routes[0].cameras[figure_frame], figure_frame, runs.runs);
  }
  section += kTraversalNotes + figure + dag_frame_budget_section(context, m, routes, out);
  write_text_file(context.options.out_dir / "dag.json", out.dump(2) + "\n");
  context.report += section;
}

}  // namespace pms::bench
