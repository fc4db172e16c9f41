// The "sender" group: kim-lee-kobbelt 2005 §7–8 on the shared models. E2 bits per vsplit packet
// (Table 2), E3 server memory per session, windowed active tags vs a stored vertex front (Fig 6),
// E4 bytes over two laps of one path (Fig 7), E5 bytes to satisfy τ from a close view, view-dependent
// vs the plain PM order (Fig 9); then E11, many clients against one server process over loopback TCP.
// E2–E5 run the server's Session in-process (LocalTransport) so its own state can be read each frame.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <thread>

#include <utility>  // before asio with C++20

#include <boost/asio.hpp>

#include "apps/bench/bench.h"
#include "apps/bench/child_process.h"
#include "apps/bench/local_transport.h"
#include "apps/bench/report.h"
#include "apps/camera_path.h"
#include "apps/percentile.h"
#include "apps/resource_usage.h"
#include "common/error.h"

namespace pms::app {
namespace fs = std::filesystem;
using nlohmann::json;
namespace {

const std::vector<std::string> kDefaultModels = {"bunny", "horse", "dragon"};
constexpr float kTolerance = 1;
constexpr uint32_t kPathFrames = 120, kQuickPathFrames = 30;
const std::vector<uint32_t> kClientCounts = {1, 10, 100, 500};
const std::vector<uint32_t> kQuickClientCounts = {1, 10};
constexpr uint32_t kE11Frames = 20;
// A stored vertex front holds one 64-bit <tree-id, node-id> (or pointer) per active node.
constexpr double kFrontEntryBytes = 8;

// kim-lee-kobbelt 2005 Fig 9: bytes until the tolerance is satisfied.
struct PaperE5 {
  const char* model;
  uint64_t view_dependent, view_independent;
};
constexpr PaperE5 kPaperE5[] = {{"bunny", 177'120, 827'688}, {"dragon", 946'400, 3'816'384}};

void print(const std::string& text) {
  std::fputs(text.c_str(), stdout);
  std::fflush(stdout);
}

struct Model {
  std::string name;
  fs::path pms;
  std::shared_ptr<const server::Catalogue> catalogue;
  const server::ServedModel* served = nullptr;
};

// `deviation` as `pmstream build --deviation` takes it.
Model prepare(const BenchContext& context, const std::string& model, const std::string& deviation = "estimate") {
  const std::string name = deviation == "estimate" ? model : model + "-" + deviation;
  Model m;
  m.name = name;
  m.pms = context.temp_dir / (name + ".pms");
  std::fprintf(stderr, "bench: building %s ... ", name.c_str());
  const ChildResult run = run_child({context.self_exe, "build", find_model(context.models_dir, model).string(), "-o",
                                     m.pms.string(), "--deviation", deviation, "--json"});
  if (!run.ok()) fail(name, "pmstream build: " + run.failure());
  std::fprintf(stderr, "%.2f s\n", run.wall_seconds);
  m.catalogue = server::Catalogue::open({m.pms.string()});
  m.served = m.catalogue->find(name);
  return m;
}

std::vector<Camera> path_of(const Model& m, PathKind kind, uint32_t frames) {
  PathOptions options;
  options.frames = frames;
  return make_camera_path(kind, m.served->view(), options);
}

// ---- E2 ------------------------------------------------------------------------------------------------

struct E2 {
  double topology = 0, position = 0, refinement = 0, total = 0;  // mean bits per packet
};

E2 packet_bits_of(const Model& m) {
  const ModelView& view = m.served->view();
  E2 e;
  uint64_t n = 0;
  for (uint32_t node : view.split_order) {
    const protocol::PacketBits b = protocol::packet_bits(split_record(view, node), m.served->context);
    e.topology += b.topology;
    e.position += b.position;
    e.refinement += b.refinement;
    e.total += b.total();
    ++n;
  }
  if (n) {
    e.topology /= double(n);
    e.position /= double(n);
    e.refinement /= double(n);
    e.total /= double(n);
  }
  return e;
}

std::string percent_of(uint64_t part, uint64_t whole) {
  return fixed(100.0 * double(part) / double(std::max<uint64_t>(whole, 1)), 1) + " %";
}

// ---- E3 / E4 -------------------------------------------------------------------------------------------

struct Laps {
  uint64_t lap_down[2] = {0, 0}, lap_up[2] = {0, 0};
  uint64_t splits = 0, payload_down = 0;
  double mean_ratio = 0, max_ratio = 0;  // windowed tags / stored front, over the frames
  uint64_t max_tag_bytes = 0, max_front_bytes = 0;
  uint64_t max_front_nodes = 0, max_window_nodes = 0;
  json frames = json::array();
};

Laps run_laps(const Model& m, const std::vector<Camera>& path) {
  auto transport = std::make_unique<LocalTransport>(m.catalogue);
  LocalTransport& local = *transport;
  client::StreamingClient client(std::move(transport), client::ClientOptions{kTolerance});
  client.open(m.name);
  Laps laps;
  double ratio_sum = 0;
  uint32_t index = 0;
  for (int lap = 0; lap < 2; ++lap)
    for (const Camera& camera : path) {
      const client::FrameReport r = client.frame(camera);
      laps.lap_down[lap] += r.down_bytes;
      laps.lap_up[lap] += r.up_bytes;
      const ActiveTags& tags = local.session().tags();
      const double front = double(tags.active_count()) * kFrontEntryBytes;
      const double ratio = double(tags.memory_bytes()) / front;
      ratio_sum += ratio;
      laps.max_ratio = std::max(laps.max_ratio, ratio);
      laps.max_tag_bytes = std::max<uint64_t>(laps.max_tag_bytes, tags.memory_bytes());
      laps.max_front_bytes = std::max<uint64_t>(laps.max_front_bytes, uint64_t(front));
      laps.max_front_nodes = std::max<uint64_t>(laps.max_front_nodes, tags.active_count());
      laps.max_window_nodes = std::max<uint64_t>(laps.max_window_nodes, tags.win_max() - tags.win_min() + 1);
      laps.frames.push_back({{"frame", index++},
                             {"lap", lap},
                             {"down_bytes", r.down_bytes},
                             {"up_bytes", r.up_bytes},
                             {"faces", r.faces},
                             {"tag_bytes", tags.memory_bytes()},
                             {"front_bytes", front},
                             {"window", tags.win_max() - tags.win_min() + 1}});
    }
  laps.mean_ratio = ratio_sum / double(2 * path.size());
  laps.splits = client.session().splits_received();
  laps.payload_down = client.counters().payload_down();
  return laps;
}

// ---- E5 ------------------------------------------------------------------------------------------------

struct E5 {
  uint64_t vd_bytes = 0, vd_faces = 0;
  uint64_t vi_bytes = 0, vi_splits = 0, vi_faces = 0;
};

// A close view: the first orbit camera moved halfway to its target (the model overflows the screen).
Camera close_view(const Model& m) {
  Camera c = path_of(m, PathKind::orbit, 1)[0];
  for (int k = 0; k < 3; ++k) c.eye[k] = 0.5f * (c.eye[k] + c.target[k]);
  return c;
}

E5 run_e5(const Model& m, const Camera& camera) {
  E5 e;
  client::StreamingClient client(std::make_unique<LocalTransport>(m.catalogue), client::ClientOptions{kTolerance});
  client.open(m.name);
  client.frame(camera);
  e.vd_bytes = client.counters().bytes_down;
  e.vd_faces = client.session().mesh().face_count();
  // The view-independent baseline streams the plain PM order (packets without refinement info) until the
  // prefix satisfies the same view: a real vi session, bytes down until that VIEW's final batch.
  client::ClientOptions vi_options{kTolerance};
  vi_options.mode = protocol::StreamMode::view_independent;
  client::StreamingClient vi(std::make_unique<LocalTransport>(m.catalogue), vi_options);
  vi.open(m.name);
  vi.frame(camera);
  e.vi_bytes = vi.counters().bytes_down;
  e.vi_splits = vi.session().splits_received();
  e.vi_faces = vi.session().mesh().face_count();
  return e;
}

// ---- E11 -----------------------------------------------------------------------------------------------

uint16_t free_port() {
  boost::asio::io_context io;
  boost::asio::ip::tcp::acceptor acceptor(io, {boost::asio::ip::make_address("127.0.0.1"), 0});
  return acceptor.local_endpoint().port();
}

struct E11 {
  uint32_t clients = 0, failed = 0;
  double server_cpu = 0, server_rss_mb = 0, seconds = 0;
  uint64_t bytes_out = 0;
  uint64_t session_state_bytes = 0;   // the largest one session held (tags, a VIEW's ranking, scratch)
  uint64_t session_buffer_bytes = 0;  // the same without the tags
  double p50 = 0, p99 = 0;
  double first_p50 = 0, first_p99 = 0, later_p99 = 0;  // a client's first VIEW (from the base mesh) and the rest
  std::string error;
};

E11 run_e11(const BenchContext& context, const Model& m, uint32_t clients) {
  E11 e;
  e.clients = clients;
  const uint16_t port = free_port();
  std::atomic<pid_t> server_pid{0};
  ChildResult server_run;
  ChildOptions options;
  options.timeout_seconds = 1800;
  options.on_start = [&](pid_t pid) { server_pid = pid; };
  std::thread server([&] {
    server_run = run_child({context.self_exe, "serve", m.pms.string(), "--host", "127.0.0.1", "--port",
                            std::to_string(port), "--max-sessions", std::to_string(clients + 16)},
                           options);
  });
  // Ready once it accepts.
  for (int attempt = 0; attempt < 600; ++attempt) {
    try {
      client::Link probe("127.0.0.1", port);
      break;
    } catch (const Error&) {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
  }
  const std::vector<Camera> orbit = path_of(m, PathKind::orbit, 360);
  std::vector<std::vector<double>> latencies(clients);
  std::atomic<uint32_t> failed{0};
  std::string first_error;
  std::mutex error_mutex;
  Stopwatch clock;
  std::vector<std::thread> threads;
  // Load clients, as wrk is for HTTP: each speaks the protocol (HELLO, OPEN, a VIEW per frame along its
  // own part of the orbit, every batch read and decoded) but does no refinement of its own, so the
  // machine's two cores go to the server and latency is the server's, not client scheduling.
  for (uint32_t i = 0; i < clients; ++i)
    threads.emplace_back([&, i] {
      try {
        client::Link link("127.0.0.1", port, 64u << 20);
        auto expect = [&](protocol::MessageType type) {
          std::optional<protocol::Frame> f = link.receive(std::chrono::seconds(120));
          if (!f) fail("E11", "no answer within 120 s");
          if (f->type == protocol::MessageType::error) fail("E11", protocol::decode_error(f->payload).text);
          if (f->type != type) fail("E11", "unexpected " + protocol::to_string(f->type));
          return std::move(*f);
        };
        link.send(protocol::encode(protocol::Hello{protocol::kProtocolVersion, "bench"}));
        expect(protocol::MessageType::hello_ok);
        link.send(protocol::encode(protocol::Open{m.name, {}}));
        const protocol::StreamContext context = protocol::stream_context(protocol::decode_base(expect(protocol::MessageType::base).payload));
        const size_t start = size_t(i) * 97 % orbit.size();
        for (uint32_t f = 0; f < kE11Frames; ++f) {
          const Stopwatch sent;
          link.send(protocol::encode(protocol::View{orbit[(start + f * 3) % orbit.size()], kTolerance, f + 1}));
          for (;;) {
            const protocol::VSplits batch = protocol::decode_vsplits(expect(protocol::MessageType::vsplits).payload, context);
            if (batch.final && batch.frame == f + 1) break;
          }
          latencies[i].push_back(1000 * sent.seconds());
        }
      } catch (const Error& err) {
        failed++;
        std::lock_guard<std::mutex> lock(error_mutex);
        if (first_error.empty()) first_error = err.what();
      }
    });
  for (std::thread& t : threads) t.join();
  e.seconds = clock.seconds();
  if (server_pid) ::kill(server_pid, SIGINT);
  server.join();
  e.failed = failed;
  e.error = first_error;
  e.server_cpu = server_run.user_seconds + server_run.system_seconds;
  // The server's own peak as it reports it; wait4's also counts this bench's pages inherited at fork.
  const size_t rss_at = server_run.out.find("peak RSS ");
  e.server_rss_mb = rss_at != std::string::npos ? std::strtod(server_run.out.c_str() + rss_at + 9, nullptr)
                                                : server_run.peak_rss_mb;
  const size_t at = server_run.out.find("bytes in, ");
  if (at != std::string::npos) e.bytes_out = std::strtoull(server_run.out.c_str() + at + 10, nullptr, 10);
  const std::string state = "peak session state ";
  const size_t state_at = server_run.out.find(state);
  if (state_at != std::string::npos) {
    char* end = nullptr;
    e.session_state_bytes = std::strtoull(server_run.out.c_str() + state_at + state.size(), &end, 10);
    if (std::strncmp(end, " bytes (", 8) == 0) e.session_buffer_bytes = std::strtoull(end + 8, nullptr, 10);
  }
  std::vector<double> all, first, later;
  for (const auto& l : latencies) {
    all.insert(all.end(), l.begin(), l.end());
    if (l.empty()) continue;
    first.push_back(l.front());
    later.insert(later.end(), l.begin() + 1, l.end());
  }
  e.p50 = percentile(all, 0.5);
  e.p99 = percentile(all, 0.99);
  e.first_p50 = percentile(first, 0.5);
  e.first_p99 = percentile(first, 0.99);
  e.later_p99 = percentile(later, 0.99);
  return e;
}

}  // namespace

void run_sender_group(BenchContext& context) {
  json out = {{"command", context.options.command_line}, {"machine", machine_json()}, {"models", json::array()}};
  std::string section = "## sender: E2 packet bits, E3 server memory, E4 two laps, E5 bytes to satisfy τ, E11 many clients\n\n";
  if (context.models_dir.empty()) {
    section += "Skipped: ../shared/models not found.\n\n";
    context.report += section;
    return;
  }
  const bool quick = context.options.quick;
  std::vector<std::string> names = context.options.models.empty() ? kDefaultModels : context.options.models;
  if (quick && context.options.models.empty()) names = {"bunny"};

  Table e2({{"model", false}, {"topology bits", true}, {"paper (Table 2)", true}, {"position bits", true},
            {"refinement bits", true}, {"bytes/packet (wire)", true}});
  Table e34({{"model", false}, {"frames", true}, {"lap 1 down B", true}, {"lap 1 up B", true}, {"lap 2 down B", true},
             {"lap 2 up B", true}, {"tags / front (mean)", true}, {"(max)", true}, {"peak tags B", true},
             {"peak front B", true}, {"front / nodes", true}, {"window / nodes", true}});
  Table e5({{"model", false}, {"VD bytes", true}, {"VD faces", true}, {"VI bytes", true}, {"VI splits", true},
            {"VD / VI", true}, {"paper VD / VI", true}});
  std::vector<Model> models;
  for (const std::string& name : names) {
    Model m = prepare(context, name);
    json record = {{"model", name}};
    const E2 bits = packet_bits_of(m);
    const std::vector<Camera> path = path_of(m, PathKind::orbit, quick ? kQuickPathFrames : kPathFrames);
    const Laps laps = run_laps(m, path);
    const double wire = laps.splits ? double(laps.payload_down) / double(laps.splits) : 0;
    e2.add_row({name, fixed(bits.topology, 1), "96", fixed(bits.position, 1), fixed(bits.refinement, 1), fixed(wire, 1)});
    e34.add_row({name, std::to_string(2 * path.size()), thousands(laps.lap_down[0]), thousands(laps.lap_up[0]),
                 thousands(laps.lap_down[1]), thousands(laps.lap_up[1]), fixed(100 * laps.mean_ratio, 1) + " %",
                 fixed(100 * laps.max_ratio, 1) + " %", thousands(laps.max_tag_bytes), thousands(laps.max_front_bytes),
                 percent_of(laps.max_front_nodes, m.served->view().node_count()),
                 percent_of(laps.max_window_nodes, m.served->view().node_count())});
    std::string paper = "";
    for (const PaperE5& p : kPaperE5)
      if (name == p.model) paper = fixed(double(p.view_dependent) / double(p.view_independent), 2);
    const E5 vd = run_e5(m, close_view(m));
    // The same model built with the deviation bound (build --deviation bound).
    const Model bounded = prepare(context, name, "bound");
    const E5 vb = run_e5(bounded, close_view(bounded));
    for (const auto& [label, e] : {std::pair{name, vd}, std::pair{name + ", bound", vb}})
      e5.add_row({label, thousands(e.vd_bytes), thousands(e.vd_faces), thousands(e.vi_bytes), thousands(e.vi_splits),
                  fixed(double(e.vd_bytes) / double(std::max<uint64_t>(1, e.vi_bytes)), 2), paper});
    record["e2"] = {{"topology_bits", bits.topology}, {"position_bits", bits.position},
                    {"refinement_bits", bits.refinement}, {"wire_bytes_per_packet", wire}};
    record["e3_e4"] = {{"lap_down", {laps.lap_down[0], laps.lap_down[1]}}, {"lap_up", {laps.lap_up[0], laps.lap_up[1]}},
                       {"tags_over_front_mean", laps.mean_ratio}, {"tags_over_front_max", laps.max_ratio},
                       {"frames", laps.frames}};
    for (const auto& [key, e] : {std::pair{"e5", vd}, std::pair{"e5_bound", vb}})
      record[key] = {{"vd_bytes", e.vd_bytes}, {"vd_faces", e.vd_faces}, {"vi_bytes", e.vi_bytes}, {"vi_splits", e.vi_splits}};
    out["models"].push_back(record);
    models.push_back(std::move(m));
  }
  print("\nE2: bits per vsplit packet (kim-lee-kobbelt Table 2: 96 topology bits)\n" + e2.markdown());
  print("\nE3/E4: two laps of an orbit at τ = 1 px (Fig 6: tags ≈ 10 % of a stored front; Fig 7: lap 2 = 0)\n" + e34.markdown());
  print("\nE5: bytes to satisfy τ = 1 px from a close view (Fig 9)\n" + e5.markdown());
  section += "### E2: bits per vsplit packet\n\n" + e2.markdown() +
             "\nTopology = ids of v_s, v̂_l, v̂_r and the cut flags, written with the model's tree/node id widths.\n\n";
  section += "### E3/E4: two laps of one orbit path, τ = 1 px\n\n" + e34.markdown() +
             "\nA stored front costs " + fixed(kFrontEntryBytes, 0) + " bytes per active node (one 64-bit id). The tags cost "
             "a bit per node of the window, which spans from the coarsest active node to the finest, so tags / front "
             "≈ window / (64 × front): at most 10 % needs a front of at least a sixth of the window (peak columns, "
             "as a share of the hierarchy's nodes). A front that mixes unrefined coarse nodes with leaves spans "
             "most nodes in any parents-first order: PM order instead of breadth-first shrank the window by a third at "
             "most on bunny and dragon. Within a level, sibling pairs come largest parent deviation first, which "
             "ends the window sooner (docs/internals.md).\n\n";
  section += "### E5: bytes to satisfy τ = 1 px from a close view\n\n" + e5.markdown() +
             "\nVI = a view-independent session (`stream --mode vi`) to the same view: the base mesh plus the plain "
             "PM-order prefix (packets without refinement info) up to the last split the view needs, bytes down until "
             "that VIEW's final batch. \"bound\" rows: the model built with `--deviation bound` (a bound on the input "
             "surface below each node, whose chain over-refines a close view) instead of the default, Hoppe 1997's "
             "sampled estimate (the criteria the paper uses).\n\n";

  // E11 on the largest model asked for.
  const Model& big = models.back();
  Table e11({{"clients", true}, {"failed", true}, {"server CPU s", true}, {"server peak RSS MB", true},
             {"peak session KB", true}, {"without tags KB", true},
             {"bytes out", true}, {"latency p50 ms", true}, {"p99 ms", true}, {"first VIEW p50 ms", true},
             {"first p99 ms", true}, {"later p99 ms", true}, {"wall s", true}});
  json e11_json = json::array();
  for (uint32_t n : quick ? kQuickClientCounts : kClientCounts) {
    std::fprintf(stderr, "bench: E11 %u clients on %s ... ", n, big.name.c_str());
    const E11 e = run_e11(context, big, n);
    std::fprintf(stderr, "%.1f s\n", e.seconds);
    e11.add_row({std::to_string(n), std::to_string(e.failed), fixed(e.server_cpu, 2), fixed(e.server_rss_mb, 0),
                 fixed(double(e.session_state_bytes) / 1024, 1), fixed(double(e.session_buffer_bytes) / 1024, 1),
                 thousands(e.bytes_out), fixed(e.p50, 2), fixed(e.p99, 2), fixed(e.first_p50, 2), fixed(e.first_p99, 2),
                 fixed(e.later_p99, 2), fixed(e.seconds, 1)});
    e11_json.push_back({{"clients", n}, {"failed", e.failed}, {"error", e.error}, {"server_cpu_seconds", e.server_cpu},
                        {"server_peak_rss_mb", e.server_rss_mb}, {"peak_session_state_bytes", e.session_state_bytes},
                        {"peak_session_bytes_without_tags", e.session_buffer_bytes},
                        {"bytes_out", e.bytes_out}, {"p50_ms", e.p50},
                        {"p99_ms", e.p99}, {"first_view_p50_ms", e.first_p50}, {"first_view_p99_ms", e.first_p99},
                        {"later_views_p99_ms", e.later_p99}, {"seconds", e.seconds}});
  }
  out["e11"] = e11_json;
  print("\nE11: clients against one server process on " + big.name + " (" + std::to_string(kE11Frames) +
        " frames each, loopback TCP)\n" + e11.markdown());
  section += "### E11: many clients, one server (" + big.name + ")\n\n" + e11.markdown() + "\n";
  write_text_file(context.options.out_dir / "sender.json", out.dump(2) + "\n");
  context.report += section;
}

}  // namespace pms::app
