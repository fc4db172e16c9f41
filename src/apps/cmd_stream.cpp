// pmstream stream --server HOST:PORT|ws://HOST:PORT/ws --model NAME --path PATH.json --mode MODE --tolerance PX
//                 (--mode receiver: --server http://HOST:PORT[/prefix] [--in-flight N] [--fetch lists|blocks]
//                  [--ranking error|area] [--stop-area PIXELS]
//                  [--ids-per-request N] [--descendant-depth K] [--block-depth K] [--frame-budget-ms MS]
//                  [--frame-answers N] [--prefetch] [--rerank-ms MS] [--background-bytes N] [--ahead N])
//                 (--mode multilevel: --server http://HOST:PORT[/prefix] [--budget TRIANGLES | --tolerance PX])
//                 [--laps K] [--reconnect N] [--timeout-ms N] [--connect-timeout-ms N] [--save-mesh OUT.ply]
//                 [--snapshots DIR] [--json]
// The headless viewer: follows a camera path with the Viewer of the chosen mode (client/viewer.h), streaming
// what each frame needs, and reports per frame.
// An option the chosen mode does not use is an error (ModeOptions), never silently ignored.
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <thread>

#include "apps/camera_json.h"
#include "apps/commands.h"
#include "apps/refine_pipeline.h"
#include "apps/resource_usage.h"
#include "client/viewer.h"
#include "common/error.h"
#include "dag/traversal.h"
#include "io/mesh.h"
#include "protocol/client_messages.h"
#include "protocol/stream_mode.h"
#include "render/render.h"
#include "spm/selective_mesh.h"

namespace pms::app {
namespace {

struct StreamArgs {
  std::string server, model, path, mode = "sender", save_mesh, snapshots;
  float tolerance = 1;
  uint32_t laps = 1, morph_frames = client::kDefaultGeomorphFrames, max_ops = 0, reconnect = 0;
  uint32_t timeout_ms = 30000, connect_timeout_ms = 5000;
  uint32_t in_flight = 4, ids_per_request = 64, block_depth = client::ReceiverOptions{}.block_depth;  // receiver
  uint32_t descendant_depth = client::ReceiverOptions{}.descendant_depth;
  std::string fetch = client::fetch_policy_name(client::ReceiverOptions{}.fetch);
  std::string ranking = client::ranking_name(client::ReceiverOptions{}.ranking);
  uint32_t stop_area = client::ReceiverOptions{}.stop_area;
  uint32_t frame_budget_ms = 0, frame_answers = 0;
  bool prefetch = false;
  uint32_t ahead = 0;  // sender, with --fps
  uint32_t rerank_ms = client::ReceiverOptions{}.rerank_ms;
  uint64_t background_bytes = 0;
  std::string traversal = "priority", management = "fixed";  // dag mode
  uint64_t budget = 0;
  bool json = false;
  bool plain_levels = false;  // multilevel mode
  uint32_t fps = 0;           // 0: lock-step
};

void snapshot(const client::Viewer& viewer, const Camera& camera, const std::string& dir, size_t index,
              Renderer& renderer, Image& image) {
  const Mesh mesh = viewer.mesh();
  renderer.render({mesh.positions, mesh.indices, mesh.colors}, viewer.view_params(camera), image);
  char name[32];
  std::snprintf(name, sizeof name, "frame_%05zu.png", index);
  save_png((std::filesystem::path(dir) / name).string(), image);
}

nlohmann::json frame_json(const client::Viewer& viewer, const client::ViewerReport& r, size_t index, uint32_t lap,
                          double frame_ms) {
  const bool levels = viewer.received_unit() == std::string("levels");
  nlohmann::json f = {{"frame", index},
                      {"lap", lap},
                      {"up_bytes", r.up_bytes},
                      {"down_bytes", r.down_bytes},
                      {"faces", r.faces},
                      {levels ? "levels_received" : "vsplits", r.received},
                      {"latency_ms", r.latency_ms},
                      {"in_flight", r.in_flight},
                      {"satisfied", r.satisfied},
                      {"frame_ms", frame_ms}};
  if (r.details.is_object()) f.update(r.details);
  return f;
}

void progress(const StreamArgs& args, size_t index, size_t frames, const client::ViewerReport& r) {
  if (!args.json)
    std::fprintf(stderr, "\rframe %zu/%zu  faces %llu  down %llu B", index + 1, frames, (unsigned long long)r.faces,
                 (unsigned long long)r.down_bytes);
}

client::HttpOptions http_options(const StreamArgs& args) {
  client::HttpOptions http;
  http.in_flight = args.in_flight;
  http.io_timeout = std::chrono::milliseconds(args.timeout_ms);
  http.connect_timeout = std::chrono::milliseconds(args.connect_timeout_ms);
  return http;
}

// --mode dag: MANAGE-TRAVERSAL's parameters; --budget 0 is FREE mode, --max-ops 0 the paper's N = 300.
protocol::DagView dag_request(const StreamArgs& args) {
  protocol::DagView request;
  const std::optional<DagTraversal> traversal = protocol::dag_traversal_named(args.traversal);
  if (!traversal) fail("--traversal", "'" + args.traversal + "': " + protocol::kDagTraversalNames);
  request.traversal = *traversal;
  request.management = args.budget ? DagMode::budget : DagMode::free;
  request.budget = args.budget;
  request.max_ops = args.max_ops ? args.max_ops : 300;
  return request;
}

// The options only some modes use, by the modes that use them; the rest apply to every mode.
struct ModeOptions {
  std::vector<VariantOption> by_mode;   // against --mode
  std::vector<VariantOption> by_fetch;  // --mode receiver: against --fetch
  CliOption tolerance, budget;          // --mode multilevel: the screen-size rule or a triangle budget
  CliOption stop_area;                  // --mode receiver: the area ranking's stop rule, in place of τ
};

void refuse_unused(const StreamArgs& args, const ModeOptions& options) {
  if (args.mode != "receiver" && args.mode != "multilevel" && !protocol::mode_named(args.mode))
    fail("--mode", "'" + args.mode + "': this build streams in the modes " + client::viewer_mode_names());
  refuse_unused_options(options.by_mode, args.mode, "--mode " + args.mode);
  if (args.mode == "receiver") refuse_unused_options(options.by_fetch, args.fetch, "--fetch " + args.fetch);
  if (args.mode == "receiver" && args.ranking == "area" && options.tolerance.given())
    fail("--tolerance", "not used with --ranking area (its stop rule is --stop-area)");
  if (args.mode == "receiver" && args.ranking == "area" && (args.prefetch || args.background_bytes > 0))
    fail(args.prefetch ? "--prefetch" : "--background-bytes",
         "not used with --ranking area (it chooses splits by qrefine, which the plain records give no input for)");
  if (options.stop_area.given() && !(args.mode == "receiver" && args.ranking == "area"))
    fail("--stop-area", "only with --mode receiver --ranking area");
  if (args.mode == "multilevel" && options.budget.given() && options.tolerance.given())
    fail("--tolerance", "not used with --mode multilevel --budget (the budget picks the level)");
  if (args.mode == "dag" && args.management == "auto" && args.budget == 0)
    fail("--management", "auto needs --budget: it switches between FREE and BUDGET around the budget");
  if (args.mode == "dag" && args.frame_budget_ms > 0 && args.fps > 0)
    fail("--frame-budget-ms", "dag: lock-step only (free-running, an answer's time is the link's, which N does not set)");
  if (args.background_bytes > 0 && args.fps == 0)
    fail("--background-bytes", "needs --fps: a lock-step frame ends when its view is satisfied, so it has no idle time");
  if (args.ahead > 0 && args.fps == 0)
    fail("--ahead", "needs --fps: a lock-step frame ends when its view is satisfied, so it has no idle time");
}

// Every mode's options, from the command line (refuse_unused has refused those the mode does not use).
client::ViewerOptions viewer_options(const StreamArgs& args) {
  client::ViewerOptions options;
  options.mode = args.mode;
  options.server = args.server;
  options.pacing = args.fps ? client::Pacing::free_running : client::Pacing::lock_step;
  client::ClientOptions& session = options.session;
  session.tolerance = args.tolerance;
  session.morph_frames = args.morph_frames;
  session.max_ops = args.max_ops;
  session.ahead_frames = args.ahead;
  if (args.mode == "dag") {
    session.dag = dag_request(args);
    session.dag_management = {args.management == "auto", double(args.frame_budget_ms)};
  }
  session.reconnect_attempts = args.reconnect;
  session.answer_timeout = std::chrono::milliseconds(args.timeout_ms);
  session.connect_timeout = std::chrono::milliseconds(args.connect_timeout_ms);
  session.on_reconnect = [reconnect = args.reconnect](const std::string& reason, uint32_t attempt) {
    std::fprintf(stderr, "\n%s; reconnecting and resuming the session (%u/%u)\n", reason.c_str(), attempt, reconnect);
  };
  client::ReceiverOptions& receiver = options.receiver;
  receiver.tolerance = args.tolerance;
  receiver.morph_frames = args.morph_frames;
  receiver.max_ops = args.max_ops;
  if (args.mode == "receiver") receiver.fetch = client::fetch_policy_named(args.fetch);
  if (args.mode == "receiver") receiver.ranking = client::ranking_named(args.ranking);
  receiver.stop_area = args.stop_area;
  receiver.ids_per_request = args.ids_per_request;
  receiver.block_depth = args.block_depth;
  receiver.descendant_depth = args.descendant_depth;
  receiver.frame_budget_ms = args.frame_budget_ms;
  receiver.frame_answers = args.frame_answers;
  receiver.prefetch = args.prefetch;
  receiver.rerank_ms = args.rerank_ms;
  receiver.background_bytes = args.background_bytes;
  receiver.http = http_options(args);
  client::MultilevelOptions& multilevel = options.multilevel;
  multilevel.budget = args.budget;
  multilevel.tolerance = args.tolerance;
  multilevel.morph_frames = args.morph_frames;
  multilevel.compressed = !args.plain_levels;
  multilevel.http = http_options(args);
  return options;
}

// Flies the path lap after lap, then settles at the last camera; one JSON object or a summary line. With
// --fps the frames are paced as on a display, each started on its tick whatever the network does (a frame
// that overruns its tick delays the next, as a display would show it late).
void run_stream(const StreamArgs& args) {
  using FlightClock = std::chrono::steady_clock;
  const std::vector<Camera> path = load_path(args.path);
  if (!args.snapshots.empty()) std::filesystem::create_directories(args.snapshots);
  Stopwatch clock;
  const std::unique_ptr<client::Viewer> viewer = client::open_viewer(viewer_options(args), args.model);
  const double open_ms = clock.seconds() * 1000;  // connected, and the base mesh in
  nlohmann::json frames = nlohmann::json::array();
  Renderer renderer;
  Image image;
  size_t index = 0;
  const FlightClock::time_point flight_start = FlightClock::now();
  const auto tick = args.fps ? std::chrono::duration_cast<FlightClock::duration>(std::chrono::duration<double>(1.0 / args.fps))
                             : FlightClock::duration::zero();
  for (uint32_t lap = 0; lap < args.laps; ++lap) {
    for (const Camera& camera : path) {
      if (args.fps) std::this_thread::sleep_until(flight_start + tick * index);
      const FlightClock::time_point begun = FlightClock::now();
      const client::ViewerReport report = viewer->frame(camera);
      const double frame_ms = std::chrono::duration<double, std::milli>(FlightClock::now() - begun).count();
      frames.push_back(frame_json(*viewer, report, index, lap, frame_ms));
      if (!args.snapshots.empty()) snapshot(*viewer, camera, args.snapshots, index, renderer, image);
      progress(args, index, size_t(args.laps) * path.size(), report);
      ++index;
    }
  }
  if (args.fps) std::this_thread::sleep_until(flight_start + tick * index);  // the last frame's tick runs out
  const double flight_seconds = std::chrono::duration<double>(FlightClock::now() - flight_start).count();
  if (!args.json) std::fprintf(stderr, "\n");
  const FlightClock::time_point settle_start = FlightClock::now();
  viewer->settle(path.back());
  const double settle_seconds = std::chrono::duration<double>(FlightClock::now() - settle_start).count();
  const Mesh mesh = viewer->mesh();
  if (!args.save_mesh.empty()) save_ply(mesh, args.save_mesh);

  const bool levels = viewer->received_unit() == std::string("levels");
  nlohmann::json out = {{"frames", frames},
                        {"total_up_bytes", viewer->up_bytes()},
                        {"total_down_bytes", viewer->down_bytes()},
                        {levels ? "levels_received" : "vsplits_received", viewer->received_total()},
                        {"open_ms", open_ms},
                        {"pacing", args.fps ? "free-running" : "lock-step"},
                        {"fps", args.fps},
                        {"flight_seconds", flight_seconds},
                        {"settle_seconds", settle_seconds},
                        {"seconds", clock.seconds()}};
  out.update(viewer->totals());
  if (args.json) {
    std::printf("%s\n", out.dump().c_str());
    return;
  }
  if (levels && out.contains("first_picture_ms"))
    std::printf("%s: first picture after %.1f ms and %llu B; %llu of %u levels received\n", args.model.c_str(),
                out["first_picture_ms"].get<double>(), (unsigned long long)out["first_picture_bytes"].get<uint64_t>(),
                (unsigned long long)viewer->received_total(), out["levels"].get<uint32_t>());
  std::printf("%s: %zu frames, %llu %s received, %llu B up, %llu B down, %llu faces at the end (%.2f s)\n",
              args.model.c_str(), index, (unsigned long long)viewer->received_total(), viewer->received_unit(),
              (unsigned long long)viewer->up_bytes(), (unsigned long long)viewer->down_bytes(),
              (unsigned long long)(mesh.indices.size() / 3), clock.seconds());
}

}  // namespace

void add_stream_command(CliCommand& app) {
  auto args = std::make_shared<StreamArgs>();
  CliCommand cmd = app.subcommand("stream", "Headless viewer: stream a model from a server along a camera path");
  cmd.option("--server", args->server,
             "HOST:PORT of the server's TCP port, or ws://HOST:PORT/ws of its HTTP port's WebSocket; for --mode "
             "receiver and multilevel http://HOST:PORT[/prefix] of its HTTP port")
      .required();
  cmd.option("--model", args->model, "Model name in the server's catalogue").required();
  cmd.option("--path", args->path, "PATH.json (pmstream path ...)").required();
  cmd.option(
         "--mode", args->mode,
         "Streaming mode: sender (view-dependent), sender-plain (the same splits as plain vsplits for a viewer that "
         "does not refine), vi (plain PM order until the view is satisfied) receiver (the client asks for splits by id "
         "over HTTP), multilevel (levels of a multilevel mesh over HTTP, coarsest first) or dag (a thin client driven "
         "by the server's DAG traversal); docs/cli.md")
      .show_default();
  const CliOption tolerance = cmd.option("--tolerance", args->tolerance, "Screen-space error tolerance in pixels")
                                  .non_negative()
                                  .show_default();
  cmd.option("--laps", args->laps, "Times the path is flown").range(1u, 1000u).show_default();
  const CliOption reconnect =
      cmd.option("--reconnect", args->reconnect,
                 "On a lost connection, reconnect and resume the session up to N times (0.5 s apart, doubling)")
          .range(0u, 100u)
          .show_default();
  cmd.option("--timeout-ms", args->timeout_ms,
             "A server silent this long while an answer is due, or stuck mid-message, is lost")
      .range(1u, 3600000u)
      .show_default();
  cmd.option("--connect-timeout-ms", args->connect_timeout_ms, "Give up a connection attempt after this long")
      .range(1u, 3600000u)
      .show_default();
  const CliOption in_flight = cmd.option("--in-flight", args->in_flight,
                                         "receiver, multilevel: HTTP requests sent ahead of the answer being read")
                                  .range(1u, 64u)
                                  .show_default();
  const CliOption fetch =
      cmd.option("--fetch", args->fetch,
                 "receiver: lists (GET the ids it lacks) or blocks (GET the fixed subtree bands holding them, "
                 "shared by clients behind a cache); docs/protocol.md")
          .one_of({"lists", "blocks"})
          .show_default();
  constexpr const char* kRankingHelp =
      "receiver: error (screen area × squared screen error over records with refinement info; the mesh is local "
      "refinement's) or area (cheng-ooi's client: screen area alone over the plain records, stopping at "
      "--stop-area); docs/protocol.md";
  const CliOption ranking =
      cmd.option("--ranking", args->ranking, kRankingHelp).one_of({"error", "area"}).show_default();
  const CliOption stop_area =
      cmd.option("--stop-area", args->stop_area,
                 "receiver, --ranking area: a leaf whose visible faces cover fewer pixels is not split")
          .range(1u, 1u << 24)
          .show_default();
  const CliOption ids_per_request =
      cmd.option("--ids-per-request", args->ids_per_request, "receiver, lists: split ids in one GET")
          .range(1u, 1024u)
          .show_default();
  const CliOption descendant_depth =
      cmd.option("--descendant-depth", args->descendant_depth,
                 "receiver, lists: at most this many levels below a leaf many times τ off come in its GET "
                 "(0: the ids alone)")
          .range(0u, 8u)
          .show_default();
  const CliOption block_depth =
      cmd.option("--block-depth", args->block_depth, "receiver, blocks: levels below a block's root")
          .range(0u, 8u)
          .show_default();
  const CliOption frame_budget_ms =
      cmd.option("--frame-budget-ms", args->frame_budget_ms,
                 "receiver: end a frame after this long (checked between answers; 0 = until the view is satisfied); "
                 "what is left carries to the next frame; dag: choose N each frame so its answer takes this long at "
                 "most (0 = --max-ops)")
          .range(0u, 3600000u)
          .show_default();
  const CliOption frame_answers =
      cmd.option("--frame-answers", args->frame_answers,
                 "receiver: end a frame after this many answers (0 = until the view is satisfied); what is left "
                 "carries to the next frame")
          .range(0u, 1000000u)
          .show_default();
  const CliOption prefetch = cmd.flag(
      "--prefetch", args->prefetch,
      "receiver: with the view's wants all sent, fill the pipe with what the camera extrapolated from the last "
      "two frames would want");
  const CliOption ahead =
      cmd.option("--ahead", args->ahead,
                 "sender, with --fps: while the view lacks nothing and no VIEW is on the wire, have the server send "
                 "at low priority what the camera extrapolated this many frames on will want (0 = off)")
          .range(0u, 300u)
          .show_default();
  const CliOption rerank_ms =
      cmd.option("--rerank-ms", args->rerank_ms,
                 "receiver: rank the front again at least this often while the camera holds still (a moved camera "
                 "ranks at once; 0 = every frame with --fps)")
          .range(0u, 3600000u)
          .show_default();
  const CliOption background_bytes =
      cmd.option("--background-bytes", args->background_bytes,
                 "receiver, with --fps: once the view wants nothing more, keep fetching the model's remaining splits "
                 "(largest error first) until their answers reach this many bytes (0 = off)")
          .range(uint64_t(0), uint64_t(1) << 40)
          .show_default();
  const CliOption geomorph_frames =
      cmd.option("--geomorph-frames", args->morph_frames, "Blend splits and collapses over N frames (0 = off)")
          .show_default();
  const CliOption max_ops =
      cmd.option("--max-ops", args->max_ops, "vsplits + ecols per frame (0 = no cap; dag: N, 0 = 300)")
          .range(0u, protocol::kMaxDagOps)
          .show_default();
  const CliOption traversal = cmd.option("--traversal", args->traversal, "dag: priority, linear or constant")
                                  .one_of({"priority", "linear", "constant"})
                                  .show_default();
  const CliOption management =
      cmd.option("--management", args->management,
                 "dag: fixed (BUDGET mode with --budget, else FREE) or auto (FREE while the mesh plus 2 N stays "
                 "within --budget, else BUDGET: zheng-chan's management)")
          .one_of({"fixed", "auto"})
          .show_default();
  const CliOption budget =
      cmd.option(
             "--budget", args->budget,
             "dag: BUDGET mode with this many triangles (0 = FREE mode); multilevel: the finest LOD of at most this "
             "many triangles (0 = the screen-size rule with --tolerance)")
          .range(uint64_t(0), protocol::kMaxDagBudget)
          .show_default();
  cmd.option("--save-mesh", args->save_mesh, "Write the client's mesh after the last frame (PLY)")
      .writes({".ply"}, "PLY");
  cmd.option("--snapshots", args->snapshots, "Write a PNG per frame into this directory");
  const CliOption plain_levels =
      cmd.flag("--plain-levels", args->plain_levels,
               "multilevel: fetch the binary form's levels (exact float positions) instead of the compressed ones");
  cmd.option("--fps", args->fps,
             "Pace the frames at N a second as a display does, free-running: a frame never waits for the network "
             "and the flight takes frames/N seconds; then settle at the last camera (0 = lock-step: each frame "
             "waits until its view is satisfied)")
      .range(0u, 1000u)
      .show_default();
  cmd.flag("--json", args->json, "Print one JSON object");
  const std::vector<std::string> tcp = {"sender", "sender-plain", "vi", "dag"};
  const auto modes = std::make_shared<ModeOptions>(
      ModeOptions{{{reconnect, tcp},
                   {in_flight, {"receiver", "multilevel"}},
                   {fetch, {"receiver"}},
                   {ranking, {"receiver"}},
                   {ids_per_request, {"receiver"}},
                   {descendant_depth, {"receiver"}},
                   {block_depth, {"receiver"}},
                   {frame_budget_ms, {"receiver", "dag"}},
                   {frame_answers, {"receiver"}},
                   {prefetch, {"receiver"}},
                   {ahead, {"sender"}},
                   {rerank_ms, {"receiver"}},
                   {background_bytes, {"receiver"}},
                   // sender-plain, vi and dag apply what comes as it comes: no adaptation to blend or cap
                   {geomorph_frames, {"sender", "receiver", "multilevel"}},
                   {max_ops, {"sender", "receiver", "dag"}},
                   {traversal, {"dag"}},
                   {management, {"dag"}},
                   {budget, {"dag", "multilevel"}},
                   {plain_levels, {"multilevel"}}},
                  {{ids_per_request, {"lists"}}, {descendant_depth, {"lists"}}, {block_depth, {"blocks"}}},
                  tolerance,
                  budget,
                  stop_area});
  cmd.on_run([args, modes] {
    refuse_unused(*args, *modes);
    run_stream(*args);
  });
}

}  // namespace pms::app
