// The "sender" group: kim-lee-kobbelt 2005 §7–8 on the shared models. E2 bits per vsplit packet and every
// scheme of Table 2 (topology_schemes.h), E3 server memory per session, windowed active tags vs a stored
// vertex front (Fig 6), E4 bytes over two laps of the orbit and of Fig 5's look path (Fig 7), E5 bytes to
// satisfy τ from a close view, view-dependent vs the plain PM order (Fig 9), E13 faces and times per frame
// (Fig 8) and E14 three clients' meshes after the same bytes (Fig 10, sender_figures.h); then E11, many
// clients against one server process over loopback TCP.
// E2–E5 run the server's Session in-process (LocalTransport) so its own state can be read each frame.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <mutex>
#include <optional>
#include <thread>

#include "apps/camera_path.h"
#include "apps/percentile.h"
#include "apps/resource_usage.h"
#include "bench/bench.h"
#include "bench/bench_model.h"
#include "bench/report.h"
#include "bench/sender_figures.h"
#include "bench/serve_child.h"
#include "bench/split_record_bits.h"
#include "bench/topology_schemes.h"
#include "client/load_client.h"
#include "client/streaming_client.h"
#include "common/bit_stream.h"
#include "common/error.h"
#include "protocol/client_messages.h"
#include "protocol/packet_bits.h"
#include "spm/hierarchy.h"
#include "spm/split_codec.h"

namespace pms::bench {
using app::PathKind;
using app::percentile;
using app::Stopwatch;
namespace fs = std::filesystem;
using nlohmann::json;
namespace {

const std::vector<std::string> kDefaultModels = {"bunny", "horse", "dragon"};
constexpr float kTolerance = 1;
constexpr uint32_t kPathFrames = 120, kQuickPathFrames = 30;
const std::vector<uint32_t> kClientCounts = {1, 10, 100, 500};
const std::vector<uint32_t> kQuickClientCounts = {1, 10};
constexpr uint32_t kE11Frames = 20;

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

// ---- E2 ------------------------------------------------------------------------------------------------

struct E2 {
  double topology = 0, position = 0, refinement = 0, attributes = 0, total = 0;  // mean bits per packet
};

E2 packet_bits_of(const BenchModel& m) {
  const ModelData& model = m.served->model();
  E2 e;
  uint64_t n = 0;
  // A packet is v_s's id and its split record (docs/protocol.md, "VSPLITS"): topology = the id and the
  // record's cut vertices, position = its geometry, attributes = v_t's normal and color.
  const SplitCodec& codec = *m.served->tables->records().codec;
  const std::vector<uint32_t> q = grid_positions(model, m.served->context.grid.bits);
  for (uint32_t node : model.split_order) {
    BitWriter w;
    RecordBits b;
    codec.encode(split_context(model, q, node), split_payload(model, q, node), w, &b);
    e.topology += protocol::id_bits(model.id(node), m.served->context) + b.topology;
    e.position += b.geometry;
    e.refinement += b.refinement;
    e.attributes += double(b.attributes());
    e.total += protocol::id_bits(model.id(node), m.served->context) + b.total();
    ++n;
  }
  if (n) {
    for (double* v : {&e.topology, &e.position, &e.refinement, &e.attributes, &e.total}) *v /= double(n);
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
  // Per frame, over the frames: the session's front as windowed tags, and as the compact code, over a stored
  // front (one 64-bit id per active node, allocated).
  double mean_ratio = 0, max_ratio = 0;
  double compact_mean_ratio = 0, compact_max_ratio = 0;
  uint64_t max_tag_bytes = 0, max_compact_bytes = 0, max_front_bytes = 0;
  uint64_t max_front_nodes = 0, max_window_nodes = 0;
  double compact_seconds = 0, tags_seconds = 0;  // the two sessions' CPU time
  json frames = json::array();
};

// A stored front, allocated as a server would keep it: one 64-bit id per active node.
uint64_t stored_front_bytes(const ModelData& model, const ActiveTags& tags) {
  std::vector<uint64_t> ids;
  ids.reserve(tags.active_count());
  for (uint32_t v = tags.next_active(0); v != UINT32_MAX; v = tags.next_active(v + 1)) {
    const VertexId id = model.id(v);
    ids.push_back(uint64_t(id.tree) << 40 | id.node);
  }
  return ids.capacity() * sizeof(uint64_t);
}

// Two sessions fly the same laps side by side, one parking its front coded after every answer
// (park_after_ms 0; a server parks a session once it is idle) and one keeping the paper's windowed tags: the
// same splits, so the same fronts.
Laps run_laps(const BenchModel& m, const std::vector<Camera>& path) {
  server::ServerLimits compact_limits, tags_limits;
  compact_limits.park_after_ms = 0;
  tags_limits.compact_fronts = false;
  InProcessSession compact = in_process_session(m, compact_limits);
  InProcessSession windowed = in_process_session(m, tags_limits);
  const std::shared_ptr<double> compact_seconds = compact.server_seconds, tags_seconds = windowed.server_seconds;
  const std::shared_ptr<server::Session> compact_session = compact.session, tags_session = windowed.session;
  client::StreamingClient client(std::move(compact.transport), client::ClientOptions{kTolerance});
  client::StreamingClient tags_client(std::move(windowed.transport), client::ClientOptions{kTolerance});
  client.open(m.name);
  tags_client.open(m.name);
  const ModelData& model = m.served->model();
  Laps laps;
  double ratio_sum = 0, compact_sum = 0;
  uint32_t index = 0;
  for (int lap = 0; lap < 2; ++lap)
    for (const Camera& camera : path) {
      const client::FrameReport r = client.frame(camera);
      tags_client.frame(camera);
      laps.lap_down[lap] += r.down_bytes;
      laps.lap_up[lap] += r.up_bytes;
      const ActiveTags tags = tags_session->front_tags();
      const uint64_t tag_bytes = tags_session->front_bytes(), compact_bytes = compact_session->front_bytes();
      const uint64_t front = stored_front_bytes(model, tags);
      const double ratio = double(tag_bytes) / double(front), compact_ratio = double(compact_bytes) / double(front);
      ratio_sum += ratio;
      compact_sum += compact_ratio;
      laps.max_ratio = std::max(laps.max_ratio, ratio);
      laps.compact_max_ratio = std::max(laps.compact_max_ratio, compact_ratio);
      laps.max_tag_bytes = std::max(laps.max_tag_bytes, tag_bytes);
      laps.max_compact_bytes = std::max(laps.max_compact_bytes, compact_bytes);
      laps.max_front_bytes = std::max(laps.max_front_bytes, front);
      laps.max_front_nodes = std::max<uint64_t>(laps.max_front_nodes, tags.active_count());
      laps.max_window_nodes = std::max<uint64_t>(laps.max_window_nodes, tags.win_max() - tags.win_min() + 1);
      laps.frames.push_back({{"frame", index++},
                             {"lap", lap},
                             {"down_bytes", r.down_bytes},
                             {"up_bytes", r.up_bytes},
                             {"faces", r.faces},
                             {"tag_bytes", tag_bytes},
                             {"compact_bytes", compact_bytes},
                             {"front_bytes", front},
                             {"window", tags.win_max() - tags.win_min() + 1}});
    }
  laps.mean_ratio = ratio_sum / double(2 * path.size());
  laps.compact_mean_ratio = compact_sum / double(2 * path.size());
  laps.splits = client.session().splits_received();
  if (tags_client.session().splits_received() != laps.splits)
    fail("E3", "the compact and the windowed sessions sent different splits");
  laps.payload_down = client.counters().payload_down();
  laps.compact_seconds = *compact_seconds;
  laps.tags_seconds = *tags_seconds;
  return laps;
}

// ---- E5 ------------------------------------------------------------------------------------------------

struct E5 {
  uint64_t vd_bytes = 0, vd_faces = 0;
  uint64_t vi_bytes = 0, vi_splits = 0, vi_faces = 0;
  uint64_t plain_bytes =
      0;  // the same splits as VD, as plain vsplits (kim-lee-kobbelt §6.3, stream --mode sender-plain)
};

Camera close_view(const BenchModel& m) { return bench::close_view(m.served->model()); }

struct OneView {
  uint64_t bytes_down = 0, splits = 0, faces = 0;
};

// A fresh in-process session in `mode` flies to `camera`: bytes down until that VIEW's final batch.
OneView one_view(const BenchModel& m, const Camera& camera, protocol::StreamMode mode) {
  client::ClientOptions options{kTolerance};
  options.mode = mode;
  client::StreamingClient client(in_process_session(m).transport, options);
  client.open(m.name);
  client.frame(camera);
  return {client.counters().bytes_down, client.session().splits_received(), client.session().mesh().face_count()};
}

E5 run_e5(const BenchModel& m, const Camera& camera) {
  E5 e;
  const OneView vd = one_view(m, camera, protocol::StreamMode::sender_driven);
  e.vd_bytes = vd.bytes_down;
  e.vd_faces = vd.faces;
  // The view-independent baseline streams the plain PM order (packets without refinement info) until the
  // prefix satisfies the same view.
  const OneView vi = one_view(m, camera, protocol::StreamMode::view_independent);
  e.vi_bytes = vi.bytes_down;
  e.vi_splits = vi.splits;
  e.vi_faces = vi.faces;
  // §6.3's variation: the view-dependent splits with the client's actual cut vertices, no refinement info.
  e.plain_bytes = one_view(m, camera, protocol::StreamMode::sender_plain).bytes_down;
  return e;
}

// ---- E11 -----------------------------------------------------------------------------------------------

struct E11 {
  uint32_t clients = 0, failed = 0;
  double server_cpu = 0, server_rss_mb = 0, seconds = 0;
  uint64_t bytes_out = 0;
  uint64_t session_state_bytes = 0;   // the largest one session held (tags, a VIEW's ranking, scratch)
  uint64_t session_buffer_bytes = 0;  // the same without the tags
  double p50 = 0, p99 = 0;
  double first_p50 = 0, first_p99 = 0, later_p99 = 0;  // a client's first VIEW (from the base mesh) and the rest
  std::string error;                                   // the first client's failure
  std::string server_error;                            // the server's figures could not be read: the row has none
  bool ran = false;                                    // the clients ran (the server started)
};

// Each client flies its own part of one orbit, a VIEW per frame, as fast as the answers come.
std::vector<std::vector<double>> e11_latencies(const BenchModel& m, uint16_t port, uint32_t clients, E11& e) {
  const std::vector<Camera> orbit = path_of(m, PathKind::orbit, 360);
  std::vector<std::vector<double>> latencies(clients);
  std::atomic<uint32_t> failed{0};
  std::mutex error_mutex;
  std::vector<std::thread> threads;
  for (uint32_t i = 0; i < clients; ++i)
    threads.emplace_back([&, i] {
      try {
        client::LoadClient client("127.0.0.1", port, m.name);
        client.open(false);
        const size_t start = size_t(i) * 97 % orbit.size();
        for (uint32_t f = 0; f < kE11Frames; ++f)
          latencies[i].push_back(client.view(orbit[(start + f * 3) % orbit.size()], kTolerance));
      } catch (const Error& err) {
        failed++;
        const std::lock_guard<std::mutex> lock(error_mutex);
        if (e.error.empty()) e.error = err.what();
      }
    });
  for (std::thread& t : threads) t.join();
  e.failed = failed;
  return latencies;
}

// The server's own figures (its VmHWM: wait4's peak would also count this bench's pages inherited at fork).
void stop_server(ServeChild& server, E11& e) {
  try {
    const ServeStats stopped = server.stop();
    e.server_cpu = stopped.cpu_s;
    e.server_rss_mb = double(stopped.peak_rss_bytes) / (1024.0 * 1024.0);
    e.bytes_out = stopped.bytes_out;
    e.session_state_bytes = stopped.peak_state_bytes;
    e.session_buffer_bytes = stopped.peak_buffer_bytes;
  } catch (const Error& err) {
    e.server_error = err.what();
  }
}

// Over every VIEW, and apart: each client's first (from the base mesh) and the rest.
void summarize_latencies(const std::vector<std::vector<double>>& latencies, E11& e) {
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
}

E11 run_e11(const BenchContext& context, const BenchModel& m, uint32_t clients) {
  E11 e;
  e.clients = clients;
  std::optional<ServeChild> server;
  try {
    server.emplace(context.pmstream_exe,
                   std::vector<std::string>{m.pms.string(), "--max-sessions", std::to_string(clients + 16)});
  } catch (const Error& err) {
    e.server_error = err.what();
    return e;
  }
  const Stopwatch clock;
  const std::vector<std::vector<double>> latencies = e11_latencies(m, server->port(), clients, e);
  e.seconds = clock.seconds();
  e.ran = true;
  stop_server(*server, e);
  summarize_latencies(latencies, e);
  return e;
}

Table e11_table() {
  return Table({{"clients", true},
                {"failed", true},
                {"server CPU s", true},
                {"server peak RSS MB", true},
                {"peak session KB", true},
                {"without tags KB", true},
                {"bytes out", true},
                {"latency p50 ms", true},
                {"p99 ms", true},
                {"first VIEW p50 ms", true},
                {"first p99 ms", true},
                {"later p99 ms", true},
                {"wall s", true}});
}

// Without the server's own report its cells say so: a 0 there would read as a measurement.
std::vector<std::string> e11_row(const E11& e) {
  const bool server = e.server_error.empty();
  const auto from_server = [&](const std::string& cell) { return server ? cell : std::string("no report"); };
  const auto from_clients = [&](const std::string& cell) { return e.ran ? cell : std::string("not run"); };
  return {std::to_string(e.clients),
          from_clients(std::to_string(e.failed)),
          from_server(fixed(e.server_cpu, 2)),
          from_server(fixed(e.server_rss_mb, 0)),
          from_server(fixed(double(e.session_state_bytes) / 1024, 1)),
          from_server(fixed(double(e.session_buffer_bytes) / 1024, 1)),
          from_server(thousands(e.bytes_out)),
          from_clients(fixed(e.p50, 2)),
          from_clients(fixed(e.p99, 2)),
          from_clients(fixed(e.first_p50, 2)),
          from_clients(fixed(e.first_p99, 2)),
          from_clients(fixed(e.later_p99, 2)),
          from_clients(fixed(e.seconds, 1))};
}

json e11_record(const E11& e) {
  json row = {{"clients", e.clients},
              {"failed", e.failed},
              {"error", e.error},
              {"p50_ms", e.p50},
              {"p99_ms", e.p99},
              {"first_view_p50_ms", e.first_p50},
              {"first_view_p99_ms", e.first_p99},
              {"later_views_p99_ms", e.later_p99},
              {"seconds", e.seconds}};
  if (e.server_error.empty()) {
    row.update({{"server_cpu_seconds", e.server_cpu},
                {"server_peak_rss_mb", e.server_rss_mb},
                {"peak_session_state_bytes", e.session_state_bytes},
                {"peak_session_bytes_without_tags", e.session_buffer_bytes},
                {"bytes_out", e.bytes_out}});
  } else {
    row["server_error"] = e.server_error;
  }
  return row;
}

// E11 at each client count on `big`; a count whose server did not report is a failure of the run.
std::string e11_section(BenchContext& context, const BenchModel& big, bool quick, json& out) {
  Table e11 = e11_table();
  json rows = json::array();
  std::string notes;
  for (uint32_t n : quick ? kQuickClientCounts : kClientCounts) {
    std::fprintf(stderr, "bench: E11 %u clients on %s ... ", n, big.name.c_str());
    const E11 e = run_e11(context, big, n);
    std::fprintf(stderr, "%.1f s\n", e.seconds);
    e11.add_row(e11_row(e));
    rows.push_back(e11_record(e));
    if (!e.server_error.empty()) {
      notes += "- " + std::to_string(n) + " clients: **no server report**: " + e.server_error + "\n";
      context.failures.push_back("E11 " + std::to_string(n) + " clients: " + e.server_error);
    }
  }
  out["e11"] = rows;
  print("\nE11: clients against one server process on " + big.name + " (" + std::to_string(kE11Frames) +
        " frames each, loopback TCP)\n" + e11.markdown());
  return "### E11: many clients, one server (" + big.name + ")\n\n" + e11.markdown() + "\n" +
         (notes.empty() ? "" : notes + "\n");
}

// ---- E2–E5 per model ------------------------------------------------------------------------------------

Table e2_table() {
  return Table({{"model", false},
                {"topology bits", true},
                {"paper (Table 2)", true},
                {"position bits", true},
                {"refinement bits", true},
                {"normal + color bits", true},
                {"bytes/packet (wire)", true}});
}

Table e34_table() {
  return Table({{"model", false},
                {"path", false},
                {"frames", true},
                {"lap 1 down B", true},
                {"lap 1 up B", true},
                {"lap 2 down B", true},
                {"lap 2 up B", true},
                {"tags / front (mean)", true},
                {"tags / front (max)", true},
                {"compact / front (mean)", true},
                {"compact / front (max)", true},
                {"peak tags B", true},
                {"peak compact B", true},
                {"peak front B", true},
                {"server CPU compact / tags", true},
                {"front / nodes", true},
                {"window / nodes", true}});
}

Table e5_table() {
  return Table({{"model", false},
                {"VD bytes", true},
                {"VD faces", true},
                {"VI bytes", true},
                {"VI splits", true},
                {"VD / VI", true},
                {"paper VD / VI", true},
                {"VD plain bytes", true},
                {"plain / VD", true}});
}

// Table 2 on every model: a row per scheme, the 32-bit and the fitted columns per model.
Table table2(const std::vector<std::string>& names) {
  std::vector<Column> columns = {{"framework", false}, {"topological detail", false}, {"paper bits", true}};
  for (const std::string& name : names) {
    columns.push_back({name + " ids", true});
    columns.push_back({name + " @32", true});
    columns.push_back({name + " fitted", true});
  }
  return Table(columns);
}

// The rows of Table 2, each model's three cells side by side; the last row is our split records' topology
// (E2's entropy-coded column).
std::string table2_markdown(const std::vector<std::string>& names, const std::vector<std::vector<SchemeBits>>& per_model,
                            const std::vector<double>& record_topology) {
  Table t = table2(names);
  for (size_t k = 0; k < per_model.front().size(); ++k) {
    const SchemeBits& first = per_model.front()[k];
    std::vector<std::string> row = {first.framework + ", " + first.scheme, first.fields,
                                    std::to_string(first.paper_bits)};
    for (const std::vector<SchemeBits>& model : per_model)
      for (double v : {model[k].indices, model[k].bits_32, model[k].bits_fitted}) row.push_back(fixed(v, 1));
    t.add_row(row);
  }
  std::vector<std::string> row = {"pmstream split record, cut vertices entropy-coded", "v_s, v̂_l, v̂_r", "96"};
  for (double bits : record_topology)
    for (const std::string& cell : {std::string("3.0"), std::string("-"), fixed(bits, 1)}) row.push_back(cell);
  t.add_row(row);
  return t.markdown();
}

json table2_record(const std::vector<SchemeBits>& rows) {
  json out = json::array();
  for (const SchemeBits& r : rows)
    out.push_back({{"framework", r.framework},
                   {"scheme", r.scheme},
                   {"fields", r.fields},
                   {"paper_bits", r.paper_bits},
                   {"indices", r.indices},
                   {"bits_at_32", r.bits_32},
                   {"bits_fitted", r.bits_fitted}});
  return out;
}

void add_laps_row(const BenchModel& m, const char* path_name, size_t frames, const Laps& laps, Table& e34) {
  e34.add_row({m.name, path_name, std::to_string(2 * frames), thousands(laps.lap_down[0]), thousands(laps.lap_up[0]),
               thousands(laps.lap_down[1]), thousands(laps.lap_up[1]), fixed(100 * laps.mean_ratio, 1) + " %",
               fixed(100 * laps.max_ratio, 1) + " %", fixed(100 * laps.compact_mean_ratio, 1) + " %",
               fixed(100 * laps.compact_max_ratio, 1) + " %", thousands(laps.max_tag_bytes),
               thousands(laps.max_compact_bytes), thousands(laps.max_front_bytes),
               fixed(laps.compact_seconds / std::max(laps.tags_seconds, 1e-9), 2),
               percent_of(laps.max_front_nodes, m.served->model().node_count()),
               percent_of(laps.max_window_nodes, m.served->model().node_count())});
}

json laps_record(const Laps& laps) {
  return {{"lap_down", {laps.lap_down[0], laps.lap_down[1]}},
          {"lap_up", {laps.lap_up[0], laps.lap_up[1]}},
          {"tags_over_front_mean", laps.mean_ratio},
          {"tags_over_front_max", laps.max_ratio},
          {"compact_over_front_mean", laps.compact_mean_ratio},
          {"compact_over_front_max", laps.compact_max_ratio},
          {"server_cpu_compact_seconds", laps.compact_seconds},
          {"server_cpu_tags_seconds", laps.tags_seconds},
          {"frames", laps.frames}};
}

// E2 and E3/E4 on one model: a row in each table (E3/E4: one per path) and their entries in the model's
// record; Table 2's rows are returned.
std::vector<SchemeBits> run_e2_to_e4(const BenchModel& m, bool quick, Table& e2, Table& e34, json& record) {
  const E2 bits = packet_bits_of(m);
  const std::vector<SchemeBits> schemes = table2_bits(m.served->model(), m.served->context);
  const uint32_t frames = quick ? kQuickPathFrames : kPathFrames;
  const Laps laps = run_laps(m, path_of(m, PathKind::orbit, frames));
  const Laps look = run_laps(m, path_of(m, PathKind::look, frames));
  const double wire = laps.splits ? double(laps.payload_down) / double(laps.splits) : 0;
  e2.add_row({m.name, fixed(bits.topology, 1), "96", fixed(bits.position, 1), fixed(bits.refinement, 1),
              fixed(bits.attributes, 1), fixed(wire, 1)});
  add_laps_row(m, "orbit", frames, laps, e34);
  add_laps_row(m, "look", frames, look, e34);
  record["e2"] = {{"topology_bits", bits.topology},
                  {"position_bits", bits.position},
                  {"refinement_bits", bits.refinement},
                  {"attribute_bits", bits.attributes},
                  {"wire_bytes_per_packet", wire},
                  {"table2", table2_record(schemes)}};
  record["e3_e4"] = laps_record(laps);
  record["e3_e4_look"] = laps_record(look);
  return schemes;
}

// E5 on one model and on the same model built with the deviation bound (build --deviation bound).
void run_e5_pair(const BenchContext& context, const BenchModel& m, Table& e5, json& record) {
  std::string paper = "";
  for (const PaperE5& p : kPaperE5)
    if (m.name == p.model) paper = fixed(double(p.view_dependent) / double(p.view_independent), 2);
  const E5 vd = run_e5(m, close_view(m));
  const BenchModel bounded = prepare_model(context, m.name, "bound");
  const E5 vb = run_e5(bounded, close_view(bounded));
  for (const auto& [label, e] : {std::pair{m.name, vd}, std::pair{m.name + ", bound", vb}})
    e5.add_row({label, thousands(e.vd_bytes), thousands(e.vd_faces), thousands(e.vi_bytes), thousands(e.vi_splits),
                fixed(double(e.vd_bytes) / double(std::max<uint64_t>(1, e.vi_bytes)), 2), paper,
                thousands(e.plain_bytes), fixed(double(e.plain_bytes) / double(std::max<uint64_t>(1, e.vd_bytes)), 2)});
  for (const auto& [key, e] : {std::pair{"e5", vd}, std::pair{"e5_bound", vb}})
    record[key] = {{"vd_bytes", e.vd_bytes},
                   {"vd_faces", e.vd_faces},
                   {"vi_bytes", e.vi_bytes},
                   {"vi_splits", e.vi_splits},
                   {"vd_plain_bytes", e.plain_bytes}};
}

// Prints the three tables and returns their part of the report.
std::string e2_to_e5_sections(const Table& e2, const std::string& table2, const Table& e34, const Table& e5) {
  print("\nE2: bits per vsplit packet (kim-lee-kobbelt Table 2: 96 topology bits)\n" + e2.markdown());
  print("\nE2: Table 2's schemes on our splits (topology bits per split)\n" + table2);
  print("\nE3/E4: two laps of the orbit and of the look path at τ = 1 px (Fig 6: tags ≈ 10 % of a stored front; "
        "Fig 7: lap 2 = 0)\n" +
        e34.markdown());
  print("\nE5: bytes to satisfy τ = 1 px from a close view (Fig 9)\n" + e5.markdown());
  std::string section =
      "### E2: bits per vsplit packet\n\n" + e2.markdown() +
      "\nTopology = v_s's id and the record's v̂_l, v̂_r (split records, docs/protocol.md \"VSPLITS\"). "
      "Position = the record's geometry; normal + color = v_t's, for a model that has them. Whole split "
      "order; the wire column is E3's first lap, frame headers included.\n\n";
  section +=
      "#### Table 2: every scheme's topological detail on our splits\n\n" + table2 +
      "\nThe paper's Table 2 (kim-lee-kobbelt §7.2) counts each framework's topological fields at 32 bits with "
      "6 neighbours assumed. Here every split of the model's PM order is replayed on its mesh M^i "
      "(`topology_schemes.cpp`; a test checks the replay ends on the engine's full mesh), so each scheme's "
      "fields are those the split really has: N(v_s) with v_l, v_r first (To et al., explicit 1-ring), the "
      "min/max ids of N(v_s) (El-Sana et al., implicit 1-ring), f_l, f_r and the four faces beside them across "
      "their other edges (Southern et al., Hoppe 1997's 4-face vsplit; the variation infers f_l, f_r). Per "
      "model: \"ids\" = mean indices per split; \"@32\" = the paper's convention, 32 bits an index; \"fitted\" "
      "= each written with a BitWriter at the model's widths (a vertex id in bit_width(nodes) bits, a face id in "
      "bit_width(faces) bits, the top value for a missing side on a boundary; the explicit 1-ring list's length "
      "as an Elias-γ code, which no fixed count can replace). None of these schemes is entropy-coded; ours "
      "(\"pmstream packet\") codes the three ids with the <tree-id, node-id> code and 2 cut flags "
      "(`protocol::packet_bits`), and the last row is the split record's topology, v̂_l, v̂_r entropy-coded "
      "against v_s's ancestors' cuts (E2's first table).\n\n";
  section += "### E3/E4: two laps of the orbit and of the look path (Fig. 5), τ = 1 px\n\n" + e34.markdown() +
             "\nThe look path is Fig. 5's navigation: one turn around the model at the orbit's distance, looking from "
             "60° above to 60° below, flown twice as the paper does (`pmstream path look`). "
             "Two sessions fly each path side by side: one keeps the paper's windowed tags, one parks its front "
             "as a CompactFront after every answer (`serve --park-after-ms 0`; a server parks a session once it "
             "is idle), and each column is the session's own allocation (`front_bytes()`) over a stored front, "
             "allocated as one 64-bit id per active node. \"server CPU\" is the two sessions' thread CPU time in "
             "receive() and pump(): the compact one decodes and codes its front once per VIEW. The tags cost "
             "a bit per node of the window, which spans from the coarsest active node to the finest, so tags / front "
             "≈ window / (64 × front): at most 10 % needs a front of at least a sixth of the window (peak columns, "
             "as a share of the hierarchy's nodes). A front that mixes unrefined coarse nodes with leaves spans "
             "most nodes in any parents-first order: PM order instead of breadth-first shrank the window by a third at "
             "most on bunny and dragon. Within a level, sibling pairs come largest parent deviation first, which "
             "ends the window sooner (docs/internals.md).\n\n";
  section +=
      "### E5: bytes to satisfy τ = 1 px from a close view\n\n" + e5.markdown() +
      "\nVI = a view-independent session (`stream --mode vi`) to the same view: the base mesh plus the plain "
      "PM-order prefix (packets without refinement info) up to the last split the view needs, bytes down until "
      "that VIEW's final batch. \"VD plain\" = the same view in `stream --mode sender-plain` (kim-lee-kobbelt §6.3, "
      "Fig. 10 middle column): the VD splits with the client's actual cut vertices and no refinement info. \"bound\" "
      "rows: the model built with `--deviation bound` (a bound on the input "
      "surface below each node, whose chain over-refines a close view) instead of the default, Hoppe 1997's "
      "sampled estimate (the criteria the paper uses).\n\n";
  return section;
}

}  // namespace

void run_sender_group(BenchContext& context) {
  json out = {{"command", context.options.command_line}, {"machine", machine_json()}, {"models", json::array()}};
  std::string section =
      "## sender: E2 packet bits, E3 server memory, E4 two laps, E5 bytes to satisfy τ, E13 frame costs, E14 the "
      "same bytes, E11 many clients\n\n";
  if (skipped_without_models(context, section)) return;
  const bool quick = context.options.quick;
  std::vector<std::string> names = context.options.models.empty() ? kDefaultModels : context.options.models;
  if (quick && context.options.models.empty()) names = {"bunny"};

  Table e2 = e2_table(), e34 = e34_table(), e5 = e5_table();
  std::vector<BenchModel> models;
  std::vector<std::vector<SchemeBits>> schemes;
  std::vector<double> record_topology;
  for (const std::string& name : names) {
    BenchModel m = prepare_model(context, name);
    json record = {{"model", name}};
    schemes.push_back(run_e2_to_e4(m, quick, e2, e34, record));
    record_topology.push_back(record["e2"]["topology_bits"].get<double>());
    run_e5_pair(context, m, e5, record);
    out["models"].push_back(record);
    models.push_back(std::move(m));
  }
  section += e2_to_e5_sections(e2, table2_markdown(names, schemes, record_topology), e34, e5);
  section += frame_costs_section(context, models.back(), quick, out);  // Fig. 8 on the largest model asked for
  section += budget_images_section(context, models, quick, out);
  section += e11_section(context, models.back(), quick, out);  // on the largest model asked for
  write_text_file(context.options.out_dir / "sender.json", out.dump(2) + "\n");
  context.report += section;
}

}  // namespace pms::bench
