// pmstream stream --server HOST:PORT --model NAME --path PATH.json --mode MODE --tolerance PX
//                 (--mode receiver: --server http://HOST:PORT[/prefix] [--in-flight N] [--fetch lists|blocks]
//                  [--ids-per-request N] [--descendant-depth K] [--block-depth K] [--frame-budget-ms MS]
//                  [--frame-answers N] [--prefetch])
//                 (--mode multilevel: --server http://HOST:PORT[/prefix] [--budget TRIANGLES | --tolerance PX])
//                 [--laps K] [--reconnect N] [--timeout-ms N] [--connect-timeout-ms N] [--save-mesh OUT.ply]
//                 [--snapshots DIR] [--json]
// The headless viewer: follows a camera path, streaming what each frame needs, and reports per frame.
// An option the chosen mode does not use is an error (ModeOptions), never silently ignored.
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>

#include "apps/camera_json.h"
#include "apps/commands.h"
#include "apps/refine_pipeline.h"
#include "apps/resource_usage.h"
#include "client/http_connection.h"
#include "client/multilevel_client.h"
#include "client/receiver_client.h"
#include "client/streaming_client.h"
#include "client/transport.h"
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
  uint32_t laps = 1, morph_frames = 0, max_ops = 0, reconnect = 0;
  uint32_t timeout_ms = 30000, connect_timeout_ms = 5000;
  uint32_t in_flight = 4, ids_per_request = 64, block_depth = client::ReceiverOptions{}.block_depth;  // receiver
  uint32_t descendant_depth = client::ReceiverOptions{}.descendant_depth;
  std::string fetch = client::fetch_policy_name(client::ReceiverOptions{}.fetch);
  uint32_t frame_budget_ms = 0, frame_answers = 0;
  bool prefetch = false;
  std::string traversal = "priority";  // dag mode
  uint64_t budget = 0;
  bool json = false;
  bool plain_levels = false;  // multilevel mode
};

void split_host_port(const std::string& text, std::string& host, uint16_t& port) {
  const size_t colon = text.rfind(':');
  if (colon == std::string::npos || colon == 0) fail("--server", "'" + text + "' is not HOST:PORT");
  host = text.substr(0, colon);
  try {
    const unsigned long value = std::stoul(text.substr(colon + 1));
    if (value == 0 || value > 65535) throw std::out_of_range("port");
    port = uint16_t(value);
  } catch (const std::exception&) {
    fail("--server", "'" + text + "' has no valid port");
  }
}

// The multilevel client holds no session: its mesh and view are its own.
Mesh current_mesh(client::MultilevelClient& client) { return client.current_mesh(); }
ViewParams view_of(client::MultilevelClient& client, const Camera& camera) { return client.view_params(camera); }

template <class Client>
ViewParams view_of(Client& client, const Camera& camera) {
  return client.session().view_params(camera);
}

template <class Client>
Mesh current_mesh(Client& client) {
  MeshArrays arrays;
  client.session().refinement().extract(arrays);
  return to_mesh(std::move(arrays));
}

template <class Client>
void snapshot(Client& client, const Camera& camera, const std::string& dir, size_t index, Renderer& renderer,
              Image& image) {
  const Mesh mesh = current_mesh(client);
  renderer.render({mesh.positions, mesh.indices, mesh.colors}, view_of(client, camera), image);
  char name[32];
  std::snprintf(name, sizeof name, "frame_%05zu.png", index);
  save_png((std::filesystem::path(dir) / name).string(), image);
}

nlohmann::json frame_json(const client::FrameReport& r, size_t index, uint32_t lap) {
  return {{"frame", index},   {"lap", lap},           {"up_bytes", r.up_bytes},    {"down_bytes", r.down_bytes},
          {"faces", r.faces}, {"vsplits", r.vsplits}, {"latency_ms", r.latency_ms}};
}

void progress(const StreamArgs& args, size_t index, size_t frames, const client::FrameReport& r) {
  if (!args.json)
    std::fprintf(stderr, "\rframe %zu/%zu  faces %llu  down %llu B", index + 1, frames, (unsigned long long)r.faces,
                 (unsigned long long)r.down_bytes);
}

void print_report(const StreamArgs& args, nlohmann::json& out, size_t frames, uint64_t splits, uint64_t up,
                  uint64_t down, uint64_t faces, double seconds, const char* received = "vsplits") {
  if (args.json) {
    std::printf("%s\n", out.dump().c_str());
  } else {
    std::printf("%s: %zu frames, %llu %s received, %llu B up, %llu B down, %llu faces at the end (%.2f s)\n",
                args.model.c_str(), frames, (unsigned long long)splits, received, (unsigned long long)up,
                (unsigned long long)down, (unsigned long long)faces, seconds);
  }
}

// Flies the path lap after lap: `frame(camera, index, lap)` runs one frame and returns its JSON and
// report; snapshots, the progress line and the settling after the last camera are the same for every
// client. Returns the frames' JSON and how many frames were flown.
template <class Client, class Frame>
std::pair<nlohmann::json, size_t> fly(const StreamArgs& args, const std::vector<Camera>& path, Client& client,
                                      Frame&& frame) {
  nlohmann::json frames = nlohmann::json::array();
  Renderer renderer;
  Image image;
  size_t index = 0;
  for (uint32_t lap = 0; lap < args.laps; ++lap) {
    for (const Camera& camera : path) {
      auto [json, report] = frame(camera, index, lap);
      frames.push_back(std::move(json));
      if (!args.snapshots.empty()) snapshot(client, camera, args.snapshots, index, renderer, image);
      progress(args, index, size_t(args.laps) * path.size(), report);
      ++index;
    }
  }
  if (!args.json) std::fprintf(stderr, "\n");
  client.settle(path.back());
  if (!args.save_mesh.empty()) save_ply(current_mesh(client), args.save_mesh);
  return {std::move(frames), index};
}

// What the HTTP modes need before they fly: the server's URL, the path, the snapshot folder made.
struct HttpFlight {
  client::HttpUrl url;
  std::vector<Camera> path;
};

HttpFlight http_flight(const StreamArgs& args) {
  HttpFlight flight{client::parse_http_url(args.server), load_path(args.path)};
  if (!args.snapshots.empty()) std::filesystem::create_directories(args.snapshots);
  return flight;
}

client::HttpOptions http_options(const StreamArgs& args) {
  client::HttpOptions http;
  http.in_flight = args.in_flight;
  http.io_timeout = std::chrono::milliseconds(args.timeout_ms);
  http.connect_timeout = std::chrono::milliseconds(args.connect_timeout_ms);
  return http;
}

// --mode receiver: no session, GETs over HTTP (client/receiver_client.h); byte counts are HTTP's, headers
// included, with the payload apart.
void run_receiver(const StreamArgs& args) {
  const HttpFlight flight = http_flight(args);
  const std::vector<Camera>& path = flight.path;
  Stopwatch clock;
  client::ReceiverOptions options;
  options.tolerance = args.tolerance;
  options.morph_frames = args.morph_frames;
  options.max_ops = args.max_ops;
  options.fetch = client::fetch_policy_named(args.fetch);
  options.ids_per_request = args.ids_per_request;
  options.block_depth = args.block_depth;
  options.descendant_depth = args.descendant_depth;
  options.frame_budget_ms = args.frame_budget_ms;
  options.frame_answers = args.frame_answers;
  options.prefetch = args.prefetch;
  options.http = http_options(args);
  client::ReceiverClient client(flight.url, options);
  client.open(args.model);
  uint64_t unsatisfied = 0;
  const auto [frames, index] = fly(args, path, client, [&](const Camera& camera, size_t frame, uint32_t lap) {
    const client::ReceiverFrame r = client.frame(camera);
    nlohmann::json f = frame_json(r.report, frame, lap);
    f["down_payload_bytes"] = r.payload_down;
    f["split_requests"] = r.split_requests;
    f["cache_hits"] = r.cache_hits;
    f["rounds"] = r.rounds;
    f["satisfied"] = r.satisfied;
    f["queued"] = r.queued;
    f["in_flight"] = r.in_flight;
    f["cancelled"] = r.cancelled;
    f["stale_arrivals"] = r.stale_arrivals;
    f["prefetched"] = r.prefetched;
    f["prefetch_used"] = r.prefetch_used;
    unsatisfied += !r.satisfied;
    return std::pair{std::move(f), r.report};
  });
  const client::HttpCounters& c = client.counters();
  nlohmann::json out = {{"frames", frames},
                        {"total_up_bytes", c.bytes_up},
                        {"total_down_bytes", c.bytes_down},
                        {"total_down_payload_bytes", c.payload_down},
                        {"http_requests", c.requests},
                        {"split_requests", client.split_requests()},
                        {"requested_ids", client.totals().requested_ids},
                        {"request_code_bytes", client.totals().request_code_bytes},
                        {"cache_hits", client.cache_hits()},
                        {"fetch", args.fetch},
                        {"frame_budget_ms", args.frame_budget_ms},
                        {"frame_answers", args.frame_answers},
                        {"prefetch", args.prefetch},
                        {"frames_unsatisfied", unsatisfied},
                        {"settle_frames", client.settle_frames()},
                        {"cancelled", client.totals().cancelled},
                        {"stale_arrivals", client.totals().stale_arrivals},
                        {"prefetched", client.totals().prefetched},
                        {"prefetch_used", client.totals().prefetch_used},
                        {"http_connections", c.connections},
                        {"vsplits_received", client.session().splits_received()},
                        {"seconds", clock.seconds()}};
  print_report(args, out, index, client.session().splits_received(), c.bytes_up, c.bytes_down,
               client.session().mesh().face_count(), clock.seconds());
}

// --mode multilevel: levels over HTTP, coarsest first (client/multilevel_client.h); byte counts are HTTP's.
void run_multilevel(const StreamArgs& args) {
  const HttpFlight flight = http_flight(args);
  const std::vector<Camera>& path = flight.path;
  Stopwatch clock;
  client::MultilevelOptions options;
  options.budget = args.budget;
  options.tolerance = args.tolerance;
  options.morph_frames = args.morph_frames;
  options.compressed = !args.plain_levels;
  options.http = http_options(args);
  client::MultilevelClient client(flight.url, options);
  client.open(args.model);
  uint64_t levels_received = 0;
  const auto [frames, index] = fly(args, path, client, [&](const Camera& camera, size_t frame, uint32_t lap) {
    const client::MultilevelFrame r = client.frame(camera);
    nlohmann::json f = frame_json(r.report, frame, lap);
    f.erase("vsplits");
    f["levels_received"] = r.report.vsplits;
    f["down_payload_bytes"] = r.payload_down;
    f["wanted_level"] = r.wanted_level;
    f["level"] = r.level;
    f["levels_loaded"] = r.levels_loaded;
    f["lod_ms"] = r.lod_ms;
    levels_received += r.report.vsplits;
    return std::pair{std::move(f), r.report};
  });
  nlohmann::json arrivals = nlohmann::json::array();
  for (const client::LevelArrival& a : client.arrivals())
    arrivals.push_back({{"level", a.level},
                        {"bytes", a.bytes},
                        {"down_bytes", a.down_bytes},
                        {"down_payload_bytes", a.payload_down},
                        {"ms", a.ms}});
  const client::HttpCounters& c = client.counters();
  nlohmann::json out = {{"frames", frames},
                        {"total_up_bytes", c.bytes_up},
                        {"total_down_bytes", c.bytes_down},
                        {"total_down_payload_bytes", c.payload_down},
                        {"http_requests", c.requests},
                        {"http_connections", c.connections},
                        {"rule", args.budget ? "budget" : "screen"},
                        {"form", options.compressed ? "compressed" : "plain"},
                        {"levels", client.loader().level_count()},
                        {"levels_received", client.arrivals().size()},
                        {"arrivals", arrivals},
                        {"seconds", clock.seconds()}};
  if (!client.arrivals().empty()) {
    const client::LevelArrival& first = client.arrivals().front();
    out["first_picture_ms"] = first.ms;
    out["first_picture_bytes"] = first.down_bytes;
    out["first_picture_payload_bytes"] = first.payload_down;
  }
  if (!args.json)
    std::printf("%s: first picture after %.1f ms and %llu B; %zu of %u levels received\n", args.model.c_str(),
                client.arrivals().empty() ? 0.0 : client.arrivals().front().ms,
                (unsigned long long)(client.arrivals().empty() ? 0 : client.arrivals().front().down_bytes),
                client.arrivals().size(), client.loader().level_count());
  print_report(args, out, index, client.arrivals().size(), c.bytes_up, c.bytes_down, client.lod().indices().size() / 3,
               clock.seconds(), "levels");
}

// --mode dag: MANAGE-TRAVERSAL's parameters; --budget 0 is FREE mode, --max-ops 0 the paper's N = 300.
protocol::DagView dag_request(const StreamArgs& args) {
  protocol::DagView request;
  if (args.traversal == "priority") request.traversal = DagTraversal::priority;
  else if (args.traversal == "linear") request.traversal = DagTraversal::linear;
  else if (args.traversal == "constant") request.traversal = DagTraversal::constant_time;
  else fail("--traversal", "'" + args.traversal + "': priority, linear or constant");
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
};

void refuse_unused(const StreamArgs& args, const ModeOptions& options) {
  if (args.mode != "receiver" && args.mode != "multilevel" && !protocol::mode_named(args.mode))
    fail("--mode", "'" + args.mode + "': this build streams in the modes " + protocol::mode_names() +
                       ", receiver and multilevel");
  refuse_unused_options(options.by_mode, args.mode, "--mode " + args.mode);
  if (args.mode == "receiver") refuse_unused_options(options.by_fetch, args.fetch, "--fetch " + args.fetch);
  if (args.mode == "multilevel" && options.budget.given() && options.tolerance.given())
    fail("--tolerance", "not used with --mode multilevel --budget (the budget picks the level)");
}

void run_stream(const StreamArgs& args) {
  if (args.mode == "receiver") return run_receiver(args);
  if (args.mode == "multilevel") return run_multilevel(args);
  const std::optional<protocol::StreamMode> mode = protocol::mode_named(args.mode);
  if (!mode) fail("--mode", "'" + args.mode + "': this build streams in the modes " + protocol::mode_names());
  std::string host;
  uint16_t port = 0;
  split_host_port(args.server, host, port);
  const std::vector<Camera> path = load_path(args.path);
  if (!args.snapshots.empty()) std::filesystem::create_directories(args.snapshots);

  Stopwatch clock;
  client::ClientOptions options;
  options.tolerance = args.tolerance;
  options.morph_frames = args.morph_frames;
  options.max_ops = args.max_ops;
  options.mode = *mode;
  if (*mode == protocol::StreamMode::dag) options.dag = dag_request(args);
  options.reconnect_attempts = args.reconnect;
  options.answer_timeout = std::chrono::milliseconds(args.timeout_ms);
  options.connect_timeout = std::chrono::milliseconds(args.connect_timeout_ms);
  options.on_reconnect = [&](const std::string& reason, uint32_t attempt) {
    std::fprintf(stderr, "\n%s; reconnecting and resuming the session (%u/%u)\n", reason.c_str(), attempt,
                 args.reconnect);
  };
  client::StreamingClient client(host, port, options);
  client.open(args.model);

  const auto [frames, index] = fly(args, path, client, [&](const Camera& camera, size_t frame, uint32_t lap) {
    const client::FrameReport r = client.frame(camera);
    return std::pair{frame_json(r, frame, lap), r};
  });

  const client::LinkCounters c = client.counters();
  nlohmann::json out = {{"frames", frames},
                        {"total_up_bytes", c.bytes_up},
                        {"total_down_bytes", c.bytes_down},
                        {"total_up_payload_bytes", c.payload_up()},
                        {"total_down_payload_bytes", c.payload_down()},
                        {"vsplits_received", client.session().splits_received()},
                        {"seconds", clock.seconds()}};
  print_report(args, out, index, client.session().splits_received(), c.bytes_up, c.bytes_down,
               client.session().mesh().face_count(), clock.seconds());
}

}  // namespace

void add_stream_command(CliCommand& app) {
  auto args = std::make_shared<StreamArgs>();
  CliCommand cmd = app.subcommand("stream", "Headless viewer: stream a model from a server along a camera path");
  cmd.option("--server", args->server,
             "HOST:PORT of the server's TCP port; for --mode receiver and multilevel http://HOST:PORT[/prefix] of its "
             "HTTP port")
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
                 "what is left carries to the next frame")
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
  cmd.flag("--json", args->json, "Print one JSON object");
  const std::vector<std::string> tcp = {"sender", "sender-plain", "vi", "dag"};
  const auto modes = std::make_shared<ModeOptions>(
      ModeOptions{{{reconnect, tcp},
                   {in_flight, {"receiver", "multilevel"}},
                   {fetch, {"receiver"}},
                   {ids_per_request, {"receiver"}},
                   {descendant_depth, {"receiver"}},
                   {block_depth, {"receiver"}},
                   {frame_budget_ms, {"receiver"}},
                   {frame_answers, {"receiver"}},
                   {prefetch, {"receiver"}},
                   // sender-plain, vi and dag apply what comes as it comes: no adaptation to blend or cap
                   {geomorph_frames, {"sender", "receiver", "multilevel"}},
                   {max_ops, {"sender", "receiver", "dag"}},
                   {traversal, {"dag"}},
                   {budget, {"dag", "multilevel"}},
                   {plain_levels, {"multilevel"}}},
                  {{ids_per_request, {"lists"}}, {descendant_depth, {"lists"}}, {block_depth, {"blocks"}}},
                  tolerance,
                  budget});
  cmd.on_run([args, modes] {
    refuse_unused(*args, *modes);
    run_stream(*args);
  });
}

}  // namespace pms::app
