// The "dag" group, E9 (zheng-chan 2006 §6, Figs. 6–9): dragon along the 180-frame scan route, τ = 0.1 % of
// the viewport height, N = 300, a 60,000-triangle budget. Per traversal (priority, linear, constant-time):
// the time of MANAGE-TRAVERSAL per frame, the accuracy of linear and constant-time against priority (the share
// of priority's triangles their mesh also has, every 5 frames), the fronts against the mesh, the server's
// state per session and the bytes down per frame.
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
#include "bench/mesh_faces.h"
#include "bench/report.h"
#include "client/streaming_client.h"
#include "common/error.h"
#include "dag/compact.h"
#include "dag/traversal.h"
#include "protocol/client_messages.h"
#include "server/dag_mode.h"
#include "server/session_mode.h"

namespace pms::bench {
using app::PathKind;
using app::percentile;
using app::Stopwatch;
namespace {

using nlohmann::json;

constexpr uint32_t kFrames = 180, kQuickFrames = 40;
constexpr uint32_t kMaxOps = 300;
constexpr uint64_t kBudget = 60000;
constexpr float kToleranceOfHeight = 0.001f;
constexpr uint32_t kAccuracyEvery = 5;

constexpr DagTraversal kTraversals[] = {DagTraversal::priority, DagTraversal::linear, DagTraversal::constant_time};
constexpr const char* kTraversalNames[] = {"priority", "linear", "constant-time"};

// The share of `reference`'s faces that `faces` holds too, in percent (both sorted).
double shared_percent(const std::vector<IdFace>& faces, const std::vector<IdFace>& reference) {
  size_t common = 0;
  for (size_t i = 0, j = 0; i < faces.size() && j < reference.size();) {
    if (faces[i] < reference[j]) ++i;
    else if (reference[j] < faces[i]) ++j;
    else ++common, ++i, ++j;
  }
  return reference.empty() ? 100 : 100.0 * double(common) / double(reference.size());
}

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
  std::vector<double> accuracy;              // against priority's samples: the share of priority's triangles it has
  std::vector<double> precision;             // the share of its own triangles that priority's mesh has
};

const server::DagSessionMode& dag_mode_of(const InProcessSession& local) {
  return dynamic_cast<const server::DagSessionMode&>(*local.session->session_mode());
}

TraversalRun run_traversal(const BenchModel& m, const std::vector<Camera>& route, DagTraversal traversal) {
  const float tolerance = kToleranceOfHeight * float(route[0].height);
  InProcessSession local = in_process_session(m);
  client::ClientOptions options{tolerance};
  options.mode = protocol::StreamMode::dag;
  options.dag.traversal = traversal;
  options.dag.management = DagMode::budget;
  options.dag.budget = kBudget;
  options.dag.max_ops = kMaxOps;
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

std::string plots(const BenchContext& context, const TraversalRun (&runs)[3]) {
  Plot time{"DAG traversal time per frame", "frame", "ms (log)", "", false, true, {}};
  Plot accuracy{
      "Correct triangles against priority, every 5 frames", "frame", "% of priority's triangles", "", false, false, {}};
  Plot fronts{"Fronts against the mesh", "frame", "(Fc + Fs) / triangles", "triangles", false, false, {}};
  for (int t = 0; t < 3; ++t) {
    const std::vector<double> frames = all_frames(runs[t].triangles.size());
    time.series.push_back({kTraversalNames[t], all_frames(runs[t].frame_ms.size(), 1), runs[t].frame_ms});
    if (t > 0)
      accuracy.series.push_back({kTraversalNames[t], sample_frames(runs[t].accuracy.size()), runs[t].accuracy});
    fronts.series.push_back({kTraversalNames[t], frames, runs[t].front_share});
    fronts.series.push_back({std::string(kTraversalNames[t]) + " triangles", frames, runs[t].triangles, true});
  }
  return plot_markdown(context.options.out_dir, time, "dag-time.png", "traversal ms per frame") +
         plot_markdown(context.options.out_dir, accuracy, "dag-accuracy.png", "accuracy against priority") +
         plot_markdown(context.options.out_dir, fronts, "dag-fronts.png", "front size against mesh size");
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

}  // namespace

void run_dag_group(BenchContext& context) {
  std::string section = "## dag: E9, the DAG of operations' traversals (zheng-chan 2006 §6)\n\n";
  if (skipped_without_models(context, section)) return;
  const bool quick = context.options.quick;
  const std::string name = context.options.models.empty() ? (quick ? "bunny" : "dragon") : context.options.models[0];
  const BenchModel m = prepare_model(context, name);
  const std::vector<Camera> route = path_of(m, PathKind::scan, quick ? kQuickFrames : kFrames);
  const uint32_t nodes = m.served->tables->dag().size();
  const float tolerance = kToleranceOfHeight * float(route[0].height);

  TraversalRun runs[3];
  for (int t = 0; t < 3; ++t) {
    std::fprintf(stderr, "bench: dag %s along %zu frames ...\n", kTraversalNames[t], route.size());
    runs[t] = run_traversal(m, route, kTraversals[t]);
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
               {"session B / node", true},
               {"session KB", true},
               {"cut KB", true},
               {"thread scratch KB", true},
               {"bytes down / frame", true}});
  json out = {{"command", context.options.command_line},
              {"machine", machine_json()},
              {"model", name},
              {"frames", route.size()},
              {"nodes", nodes},
              {"tolerance_px", tolerance},
              {"max_ops", kMaxOps},
              {"budget", kBudget},
              {"dag_bytes", m.served->tables->dag().memory_bytes()}};
  for (int t = 0; t < 3; ++t) {
    const TraversalRun& run = runs[t];
    table.add_row({kTraversalNames[t], fixed(run.first.ms, 1), thousands(uint64_t(run.first.ops)),
                   fixed(percentile(run.frame_ms, 0.5), 3), fixed(percentile(run.frame_ms, 0.99), 3),
                   fixed(percentile(run.load_ms, 0.5), 3) + " + " + fixed(percentile(run.store_ms, 0.5), 3),
                   thousands(uint64_t(mean(run.evaluated))), thousands(uint64_t(mean(run.ops))),
                   thousands(run.max_triangles), fixed(percentile(run.front_share, 0.5), 2),
                   t == 0 ? "—" : fixed(route_mean(run.accuracy), 1),
                   t == 0 ? "—" : fixed(route_mean(run.precision), 1), fixed(double(run.max_session_bytes) / nodes, 3),
                   fixed(double(run.max_session_bytes) / 1e3, 1), fixed(double(run.max_cut_bytes) / 1e3, 1),
                   fixed(double(run.max_scratch_bytes) / 1e3, 1), thousands(uint64_t(mean(run.down_bytes)))});
    out[kTraversalNames[t]] = run_json(run, nodes);
  }
  const std::string settings = name + ", " + std::to_string(route.size()) +
                               "-frame scan route, τ = " + fixed(tolerance, 3) +
                               " px (0.1 % of the height), N = " + std::to_string(kMaxOps) + ", BUDGET " +
                               thousands(kBudget) + " triangles, " + thousands(nodes) + " DAG nodes";
  print_now("\nE9: DAG traversals, " + settings +
            " (targets: constant-time ≤ 0.1 ms, priority ≤ 2 ms median; accuracy linear ≥ 80 %, constant-time ≥ 70 %; "
            "session ≤ 0.1 B / node)\n" +
            table.markdown());
  section +=
      "### Traversals along the route (" + settings + ")\n\n" + table.markdown() +
      "\nFirst view: the converged answer to the session's first view (the same for every traversal). ms: "
      "MANAGE-TRAVERSAL alone on a bare cut, fed the same views as the session, frames 1 on; load + store: the "
      "medians of decoding the compact cut into the thread's dense one and encoding it back (each turn of a session "
      "does both). Accuracy: the share "
      "of priority's triangles (by vertex ids) the client's mesh also has, every 5 frames from frame 5, averaged; "
      "precision: the share of the client's own triangles that priority's mesh has, averaged alike. "
      "Session: the "
      "DAG mode's `state_bytes()` at its largest along the route; cut: `CompactDagCut::memory_bytes()` (what a "
      "session keeps between turns); thread scratch: the dense cut and the traversals' heaps and stack one I/O "
      "thread keeps (shared by the sessions of a thread, not per session), run so far. Bytes down: "
      "DAG_OPS frames as received, mean per frame. docs/internals.md, \"E9\", says what each figure is.\n\n";
  section += plots(context, runs);
  write_text_file(context.options.out_dir / "dag.json", out.dump(2) + "\n");
  context.report += section;
}

}  // namespace pms::bench
