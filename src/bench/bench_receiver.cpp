// The "receiver" group: cheng-ooi 2008's receiver-driven mode against the sender-driven one and against
// single-rate web codecs. The whole model's bits per vertex through each (pmstream's split records and BASE
// against meshoptimizer + gzip / zstd and Draco, on the same grid); E7, what serving a split costs the
// server in CPU time and bytes out, sender- vs receiver-driven, along the same path; E6 and E8, image
// quality against bytes received and with only the visible splits fetched (receiver_quality.h).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <limits>
#include <optional>
#include <thread>

#include "apps/camera_path.h"
#include "apps/refine_pipeline.h"
#include "bench/bench.h"
#include "bench/bench_model.h"
#include "bench/e7_phases.h"
#include "bench/receiver_quality.h"
#include "bench/report.h"
#include "bench/serve_child.h"
#include "bench/single_rate_codecs.h"
#include "bench/split_record_bits.h"
#include "client/receiver_client.h"
#include "client/streaming_client.h"
#include "common/bit_stream.h"
#include "common/error.h"
#include "io/mesh.h"
#include "protocol/message_types.h"
#include "server/split_records_body.h"

namespace pms::bench {
using app::PathKind;
using app::refine_first_splits;
using nlohmann::json;
namespace {

const std::vector<std::string> kDefaultModels = {"bunny", "horse", "dragon"};
constexpr float kTolerance = 1;
constexpr uint32_t kPathFrames = 120, kQuickPathFrames = 30;
// Draco at a coarser grid too, as issue 19 quotes it (17.8 bpv on dragon at 14 bits).
constexpr uint32_t kCoarseDracoBits = 14;
// A band deeper than any model's trees.
constexpr uint32_t kWholeTree = 64;

void print(const std::string& text) {
  std::fputs(text.c_str(), stdout);
  std::fflush(stdout);
}

double per(uint64_t bits, uint64_t count) { return count ? double(bits) / double(count) : 0; }

// ---- the whole model: pmstream against single-rate codecs ----------------------------------------------

struct WholeModel {
  uint64_t vertices = 0, splits = 0;
  uint64_t base_bytes = 0, table_bytes = 0, record_bits = 0;  // the compact records (.pms SRTB / SREC)
  uint64_t wire_body_bytes = 0;                               // the HTTP bodies of every split
  SingleRateSizes single;
  uint64_t draco_coarse = 0;
  std::string draco_coarse_error;

  uint64_t records_stream_bits() const { return 8 * (base_bytes + table_bytes) + record_bits; }
};

// Every split as the receiver-driven routes send it: each tree's root with all its descendants, a band.
uint64_t wire_body_bytes(const server::ServedModel& served) {
  const ModelData& model = served.model();
  uint64_t bytes = 0;
  for (uint32_t tree = 0; tree < model.root_count; ++tree)
    if (!model.is_leaf(tree)) bytes += server::split_records_body(served, {kWholeTree, {model.id(tree)}}, {}).size();
  return bytes;
}

WholeModel measure_whole_model(const BenchModel& m) {
  const server::ServedModel& served = *m.served;
  const ModelData& model = served.model();
  WholeModel w;
  w.splits = model.split_order.size();
  w.base_bytes = served.base_frame->size() - protocol::kFrameHeaderBytes;
  BitWriter tables;
  served.file->split_codec().serialize(tables);
  w.table_bytes = tables.bytes().size();
  w.record_bits = served.file->split_offsets().empty() ? 0 : served.file->split_offsets().back();
  w.wire_body_bytes = wire_body_bytes(served);
  const Mesh finest = refine_first_splits(model, std::numeric_limits<uint64_t>::max());
  w.vertices = finest.vertex_count();
  w.single = single_rate_codecs(finest, served.context.grid);
  PositionGrid coarse = served.context.grid;
  coarse.bits = kCoarseDracoBits;
  const SingleRateSizes c = single_rate_codecs(finest, coarse);
  w.draco_coarse = c.draco;
  w.draco_coarse_error = c.draco_error;
  return w;
}

Table whole_model_table() {
  return Table({{"model", false},
                {"vertices", true},
                {"records + base + tables", true},
                {"bits / split", true},
                {"HTTP bodies", true},
                {"meshopt", true},
                {"+ gzip -9", true},
                {"+ zstd -19", true},
                {"Draco", true},
                {"Draco 14 bits", true}});
}

std::vector<std::string> whole_model_row(const std::string& name, const WholeModel& w) {
  auto bpv = [&](uint64_t bytes) { return fixed(w.single.bits_per_vertex(bytes), 1); };
  auto draco = [&](uint64_t bytes, const std::string& error) { return error.empty() ? bpv(bytes) : "failed"; };
  return {name,
          thousands(w.vertices),
          fixed(per(w.records_stream_bits(), w.vertices), 1),
          fixed(per(w.records_stream_bits(), w.splits), 1),
          bpv(w.wire_body_bytes + w.base_bytes),
          bpv(w.single.meshopt()),
          bpv(w.single.meshopt_gzip),
          bpv(w.single.meshopt_zstd),
          draco(w.single.draco, w.single.draco_error),
          draco(w.draco_coarse, w.draco_coarse_error)};
}

json whole_model_record(const WholeModel& w) {
  return {{"vertices", w.vertices},
          {"splits", w.splits},
          {"base_bytes", w.base_bytes},
          {"table_bytes", w.table_bytes},
          {"record_bits", w.record_bits},
          {"wire_body_bytes", w.wire_body_bytes},
          {"meshopt_index_bytes", w.single.meshopt_index},
          {"meshopt_vertex_bytes", w.single.meshopt_vertex},
          {"meshopt_gzip_bytes", w.single.meshopt_gzip},
          {"meshopt_zstd_bytes", w.single.meshopt_zstd},
          {"draco_bytes", w.single.draco},
          {"draco_14_bytes", w.draco_coarse}};
}

// ---- E7: server CPU and bytes out per split --------------------------------------------------------------

struct ServerCost {
  uint64_t splits = 0, bytes_out = 0, requests = 0;
  double cpu_s = 0;
  // What the receiver-driven client sent: ids its split GETs named, their codes' bytes, all its bytes up.
  uint64_t requested_ids = 0, request_code_bytes = 0, bytes_up = 0;
  PhaseMs phase_ms{};  // with `serve --profile-phases`
  std::string error;  // the flight or the server's figures failed: the row has none
};

struct Counters {
  double cpu_s = 0;
  uint64_t bytes_out = 0, splits = 0, requests = 0;
  PhaseMs phase_ms{};
};

Counters tcp_counters(const ServeStats& s) {
  return {s.cpu_s, s.bytes_out, s.splits_sent, 0, phase_ms_of(s.line.at("phases_ms"))};
}

Counters http_counters(const ServeStats& s) {
  const json& h = s.line.at("http");
  return {s.cpu_s, h.at("bytes_out").get<uint64_t>(), h.at("splits_served").get<uint64_t>(),
          h.at("requests").get<uint64_t>(), phase_ms_of(h.at("phases_ms"))};
}

// A TCP session adds its splits to the server's counters when it closes, which the client's disconnect
// only starts: the counters once no session is open, so a reading never misses the last flight's splits.
ServeStats settled_stats(ServeChild& server) {
  constexpr int kPolls = 200;  // 2 s
  for (int poll = 0;; ++poll) {
    ServeStats stats = server.stats();
    if (stats.sessions_active == 0) return stats;
    if (poll == kPolls) fail("bench", "the server still had a session open 2 s after the flight");
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
}

// The server's counters just before and just after `flight`, which flies one client along the path: what
// the flight cost, without the model's loading. `profile`: the server times its phases (e7_phases.h).
template <class Read, class Flight>
ServerCost server_cost(const BenchContext& context, const BenchModel& m, bool http, bool profile, Read read,
                       Flight flight) {
  ServerCost cost;
  try {
    // The mode's tables are built before listening: a flight pays for serving, not for a model's first use.
    std::vector<std::string> args = {m.pms.string(), "--preload", http ? "receiver" : "sender"};
    if (http) args.insert(args.end(), {"--http-port", "0"});
    if (profile) args.push_back("--profile-phases");
    ServeChild server(context.pmstream_exe, args);
    const uint16_t port = http ? server.listening().at("http_port").get<uint16_t>() : server.port();
    const Counters before = read(server.stats());
    flight(port);
    const Counters after = read(settled_stats(server));
    server.stop();
    cost.cpu_s = after.cpu_s - before.cpu_s;
    cost.bytes_out = after.bytes_out - before.bytes_out;
    cost.splits = after.splits - before.splits;
    cost.requests = after.requests - before.requests;
    for (size_t p = 0; p < cost.phase_ms.size(); ++p) cost.phase_ms[p] = after.phase_ms[p] - before.phase_ms[p];
  } catch (const std::exception& e) {
    cost.error = e.what();
  }
  return cost;
}

ServerCost sender_cost(const BenchContext& context, const BenchModel& m, const std::vector<Camera>& path,
                       bool profile = false) {
  return server_cost(context, m, false, profile, tcp_counters, [&](uint16_t port) {
    client::ClientOptions options{kTolerance};
    client::StreamingClient client("127.0.0.1", port, options);
    client.open(m.name);
    for (const Camera& camera : path) client.frame(camera);
  });
}

ServerCost receiver_cost(const BenchContext& context, const BenchModel& m, const std::vector<Camera>& path,
                         bool profile = false) {
  client::ReceiverTotals totals;
  uint64_t bytes_up = 0;
  ServerCost cost = server_cost(context, m, true, profile, http_counters, [&](uint16_t port) {
    client::ReceiverOptions options;
    options.tolerance = kTolerance;
    client::ReceiverClient client(client::HttpUrl{"127.0.0.1", port, ""}, options);
    client.open(m.name);
    for (const Camera& camera : path) client.frame(camera);
    totals = client.totals();
    bytes_up = client.counters().bytes_up;
  });
  cost.requested_ids = totals.requested_ids;
  cost.request_code_bytes = totals.request_code_bytes;
  cost.bytes_up = bytes_up;
  return cost;
}

Table e7_table() {
  return Table({{"model", false},
                {"mode", false},
                {"splits served", true},
                {"requests", true},
                {"server CPU s", true},
                {"µs / split", true},
                {"bytes out", true},
                {"bytes out / split", true},
                {"CPU vs sender", true},
                {"bytes vs sender", true}});
}

std::string ratio_change(double value, double baseline) {
  if (baseline <= 0) return "";
  const double change = 100 * (value / baseline - 1);
  std::string text = change >= 0 ? "+" : "";
  text += fixed(change, 0);
  return text + " %";
}

void add_e7_rows(BenchContext& context, const std::string& name, const ServerCost& sender, const ServerCost& receiver,
                 Table& table) {
  const double sender_us = 1e6 * sender.cpu_s / double(std::max<uint64_t>(1, sender.splits));
  const double sender_bytes = per(sender.bytes_out, sender.splits);
  for (const auto& [mode, c] : {std::pair{"sender", sender}, std::pair{"receiver", receiver}}) {
    if (!c.error.empty()) {
      context.failures.push_back("E7 " + name + " " + mode + ": " + c.error);
      print(table.add_row({name, mode, "", "", "", "", "", "", "", ""}));
      continue;
    }
    const double us = 1e6 * c.cpu_s / double(std::max<uint64_t>(1, c.splits));
    const double bytes = per(c.bytes_out, c.splits);
    const bool baseline = std::string(mode) == "sender";
    print(table.add_row({name, mode, thousands(c.splits), baseline ? "" : thousands(c.requests), fixed(c.cpu_s, 3),
                         fixed(us, 2), thousands(c.bytes_out), fixed(bytes, 1),
                         baseline ? "" : ratio_change(us, sender_us),
                         baseline ? "" : ratio_change(bytes, sender_bytes)}));
  }
}

json cost_record(const ServerCost& c) {
  return {{"splits", c.splits},
          {"requests", c.requests},
          {"cpu_s", c.cpu_s},
          {"bytes_out", c.bytes_out},
          {"requested_ids", c.requested_ids},
          {"request_code_bytes", c.request_code_bytes},
          {"client_bytes_up", c.bytes_up},
          {"error", c.error}};
}

// ---- up: bits per requested id, the E7 flights ----------------------------------------------------------

Table up_table() {
  return Table({{"model", false},
                {"split GETs", true},
                {"ids asked", true},
                {"ids / GET", true},
                {"code bits / id", true},
                {"HTTP bytes up / id", true}});
}

std::vector<std::string> up_row(const std::string& name, const ServerCost& c) {
  if (!c.error.empty()) return {name, "", "", "", "", ""};
  return {name,
          thousands(c.requests),
          thousands(c.requested_ids),
          fixed(per(c.requested_ids, c.requests), 1),
          fixed(per(8 * c.request_code_bytes, c.requested_ids), 2),
          fixed(per(c.bytes_up, c.requested_ids), 1)};
}

// ---- down: bits per split by part ------------------------------------------------------------------------

// The records by part over every split and over E5's close view (the sender group's, at τ = 1 px).
struct SplitParts {
  RecordBitsReport whole, close;
};

SplitParts measure_split_parts(const BenchModel& m) {
  const ModelData& model = m.served->model();
  const SplitCodec& codec = m.served->file->split_codec();
  const std::vector<uint32_t> q = grid_positions(model, codec.position_bits());
  SplitParts parts;
  parts.whole = record_bits(model, codec, q, model.split_order);
  parts.close = record_bits(model, codec, q, splits_for_view(model, close_view(model), kTolerance));
  return parts;
}

Table parts_table() {
  return Table({{"model", false},
                {"splits", false},
                {"count", true},
                {"topology", true},
                {"geometry", true},
                {"refinement info", true},
                {"normal + color", true},
                {"records", true},
                {"framing", true},
                {"base + tables", true},
                {"all", true}});
}

// A row each; the whole model's also gets what else the receiver-driven routes send for every split: the
// bands' presence bits and padding (framing), BASE and the code tables.
void add_parts_rows(const std::string& name, const SplitParts& parts, const WholeModel& w, Table& table) {
  for (const RecordBitsReport* r : {&parts.whole, &parts.close}) {
    const RecordBits& b = r->bits;
    const auto bits = [r](uint64_t total) { return fixed(r->per_split(total), 2); };
    std::vector<std::string> row = {name,
                                    r == &parts.whole ? "whole model" : "E5 close view",
                                    thousands(r->splits),
                                    bits(b.topology),
                                    bits(b.geometry),
                                    bits(b.refinement),
                                    bits(b.attributes()),
                                    bits(b.total()),
                                    "",
                                    "",
                                    ""};
    if (r == &parts.whole) {
      row[8] = bits(8 * w.wire_body_bytes - w.record_bits);
      row[9] = bits(8 * (w.base_bytes + w.table_bytes));
      row[10] = bits(8 * (w.wire_body_bytes + w.base_bytes + w.table_bytes));
    }
    print(table.add_row(row));
  }
}

json parts_record(const RecordBitsReport& r) {
  return {{"splits", r.splits},
          {"topology_bits", r.bits.topology},
          {"geometry_bits", r.bits.geometry},
          {"refinement_bits", r.bits.refinement},
          {"normal_bits", r.bits.normal},
          {"color_bits", r.bits.color}};
}

}  // namespace

void run_receiver_group(BenchContext& context) {
  json out = {{"command", context.options.command_line}, {"machine", machine_json()}, {"models", json::array()}};
  std::string section =
      "## receiver: whole-model bits against single-rate codecs, E7 server cost per split, E6 PSNR against bytes, E8 "
      "visible splits only\n\n";
  if (skipped_without_models(context, section)) return;
  const bool quick = context.options.quick;
  std::vector<std::string> names = context.options.models.empty() ? kDefaultModels : context.options.models;
  if (quick && context.options.models.empty()) names = {"bunny"};

  Table whole = whole_model_table(), parts = parts_table(), e7 = e7_table(), up = up_table();
  print("\nWhole model, bits per vertex at the records' position grid\n" + whole.header());
  std::vector<BenchModel> models;
  std::vector<WholeModel> wholes;
  for (const std::string& name : names) {
    models.push_back(prepare_model(context, name));
    wholes.push_back(measure_whole_model(models.back()));
    print(whole.add_row(whole_model_row(name, wholes.back())));
    out["models"].push_back({{"model", name}, {"whole", whole_model_record(wholes.back())}});
  }
  print("\nDown: bits per split by part\n" + parts.header());
  for (size_t i = 0; i < models.size(); ++i) {
    const SplitParts p = measure_split_parts(models[i]);
    add_parts_rows(models[i].name, p, wholes[i], parts);
    out["models"][i]["parts"] = {{"whole", parts_record(p.whole)}, {"close_view", parts_record(p.close)}};
  }
  print("\nE7: server CPU and bytes out per split, one client along an orbit at τ = 1 px\n" + e7.header());
  std::vector<ServerCost> receivers;
  for (size_t i = 0; i < models.size(); ++i) {
    const BenchModel& m = models[i];
    const std::vector<Camera> path = path_of(m, PathKind::orbit, quick ? kQuickPathFrames : kPathFrames);
    const ServerCost sender = sender_cost(context, m, path), receiver = receiver_cost(context, m, path);
    add_e7_rows(context, m.name, sender, receiver, e7);
    receivers.push_back(receiver);
    out["models"][i]["e7"] = {
        {"frames", path.size()}, {"sender", cost_record(sender)}, {"receiver", cost_record(receiver)}};
  }
  Table phases = e7_phase_table();
  print("\nE7 by phase (cheng-ooi Table 1): the same flights, the servers timing their phases\n" + phases.header());
  for (size_t i = 0; i < models.size(); ++i) {
    const BenchModel& m = models[i];
    const std::vector<Camera> path = path_of(m, PathKind::orbit, quick ? kQuickPathFrames : kPathFrames);
    const auto profiled = [&](const ServerCost& c) { return PhaseCost{1e3 * c.cpu_s, c.phase_ms, c.error}; };
    const PhaseCost sender = profiled(sender_cost(context, m, path, true)),
                    receiver = profiled(receiver_cost(context, m, path, true));
    for (const PhaseCost* c : {&sender, &receiver})
      if (!c->error.empty()) context.failures.push_back("E7 by phase " + m.name + ": " + c->error);
    add_e7_phase_rows(m.name, sender, receiver, phases);
    out["models"][i]["e7_phases"] = e7_phase_record(sender, receiver);
  }
  print("\nUp: bits per requested id, the receiver-driven E7 flights\n" + up.header());
  for (size_t i = 0; i < models.size(); ++i) print(up.add_row(up_row(models[i].name, receivers[i])));
  const std::string quality = e6_e8_sections(context, models, out["models"]);

  section +=
      "### The whole model, bits per vertex\n\n" + whole.markdown() +
      "\nEvery split of the model at the default 16-bit grid. \"records + base + tables\" = BASE (as `GET "
      "/models/{m}/{v}/base` sends it), the model's code tables and every compact split record (docs/protocol.md, "
      "\"Split records\"; stored in the .pms), with no HTTP framing; \"bits / split\" is the same total per split, "
      "issue 19's ≤ 40 target. \"HTTP bodies\" = BASE plus the bodies the receiver-driven routes send for "
      "every split (each tree as one band: the records with their presence bits). meshoptimizer 0.18: vertex cache "
      "then vertex fetch order, its index codec and its vertex codec on "
      "x, y, z, 0 as 16-bit lanes; gzip -9 and zstd -19 of those two streams; Draco 1.5 edgebreaker at speed 0 "
      "(`-cl 10`) with its own position quantization at 16 and at 14 bits. Every stream is decoded again and "
      "checked. The single-rate codecs have no levels of detail, no random access and no refinement info.\n\n";
  section +=
      "### Down: bits per split by part\n\n" + parts.markdown() +
      "\nBits per split, the records as stored in the .pms (docs/protocol.md, \"Split records\"): topology = the "
      "cut vertices, geometry = v_t's position, refinement info = the children's, normal + color = v_t's "
      "attributes where the model has them. \"whole model\" is every split; \"E5 close view\" the splits local "
      "refinement makes from the base mesh for the sender group's E5 close view at τ = 1 px (E6's mid view). "
      "For the whole model: framing = the receiver-driven bands' presence bits and byte padding (each tree as "
      "one band), base + tables = BASE and the code tables, all = everything a client downloads to hold every "
      "split, HTTP heads aside. Issue 19's targets: all ≤ 40 on dragon, topology + geometry ≤ 34, the close "
      "view's refinement info ≤ 24.\n\n";
  section +=
      "### E7: server CPU and bytes out per split served\n\n" + e7.markdown() +
      "\nOne `pmstream serve` child per row (TCP for sender-driven, `--http-port` for receiver-driven), one "
      "client in this process flying the same orbit at τ = 1 px. Server CPU is the child's user + system time "
      "over the flight (its counters read by SIGUSR1 before and after, and the mode's tables built before it "
      "listens, so neither loading the model nor building its tables is counted); "
      "bytes out are the server's own count (TCP payload, or HTTP headers and bodies). Issue 19's targets: "
      "CPU per split ≥ 30 % and bytes out ≥ 40 % below the sender-driven mode's (cheng-ooi: −24 % and −40 %).\n\n";
  section += "### E7 by phase: cheng-ooi's Table 1\n\n" + phases.markdown() + "\n" + e7_phase_notes();
  section += "### Up: bits per requested id\n\n" + up.markdown() +
             "\nThe receiver-driven client of the E7 flights: split GETs sent, the ids they named (each with its "
             "descendant depth, docs/protocol.md \"Receiver-driven client\"), the bits of their id sets' codes (docs/"
             "protocol.md, \"Split request code\"; whole bytes, before base64url) per id, and every byte the client "
             "sent (request lines and headers, the catalogue and BASE GETs included) per id. Issue 19's target: ≤ 27 "
             "code bits per requested id (cheng-ooi: 27).\n\n";
  section += quality;
  write_text_file(context.options.out_dir / "receiver.json", out.dump(2) + "\n");
  context.report += section;
}

}  // namespace pms::bench
