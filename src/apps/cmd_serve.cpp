// pmstream serve FILES_OR_DIRS... [--port 7300] [--http-port P] [--host 0.0.0.0] [--max-sessions N] [--json] ...
// Runs the sender-driven TCP server, and with --http-port the HTTP server beside it (the receiver-driven and
// multilevel modes, the page, the session modes' WebSocket), until SIGINT or SIGTERM; SIGUSR1 prints the
// totals so far, SIGHUP reloads the models from the paths given (serve_reload.h).
#include <pthread.h>
#include <algorithm>
#include <csignal>
#include <cstdio>
#include <ctime>
#include <nlohmann/json.hpp>

#include "apps/commands.h"
#include "apps/resource_usage.h"
#include "apps/serve_reload.h"
#include "apps/web_root.h"
#include "common/error.h"
#include "protocol/message_types.h"
#include "server/catalogue.h"
#include "server/catalogue_slot.h"
#include "server/http_server.h"
#include "server/limits.h"
#include "server/stats.h"
#include "server/tcp_server.h"

namespace pms::app {
namespace {

struct ServeArgs {
  std::vector<std::string> paths;
  std::string host = "0.0.0.0";
  uint16_t port = 7300;
  uint16_t http_port = 0;
  bool http_port_given = false;
  bool json = false;
  server::ServerLimits limits;
  server::HttpLimits http;
  std::vector<std::string> trusted_proxies;  // --trusted-proxy, parsed into http.trusted_proxies
  server::WebOptions web;                    // --web-root, --ws-allowed-origin; its sessions' limits are `limits`
  std::string preload;         // mode names, or "all"
  std::string session_front = "compact";  // --session-front: compact or tags (ServerLimits::compact_fronts)
  bool preload_given = false;  // else every table is built when first asked for
  uint32_t max_table_builds = server::TableOptions{}.max_builds;
};

uint64_t rss_bytes() {
  unsigned long long kb = 0;
  if (std::FILE* status = std::fopen("/proc/self/status", "r")) {
    char line[256];
    while (std::fgets(line, sizeof line, status))
      if (std::sscanf(line, "VmRSS: %llu kB", &kb) == 1) break;
    std::fclose(status);
  }
  return uint64_t(kb) << 10;
}

double cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

// Milliseconds spent in each of cheng-ooi's Table 1 phases (server/phase_times.h), by the phase's name.
nlohmann::json phase_ms(const server::PhaseTimes& times) {
  nlohmann::json ms = nlohmann::json::object();
  for (size_t p = 0; p < size_t(server::Phase::count); ++p) ms[server::kPhaseNames[p]] = double(times.ns[p].load()) / 1e6;
  return ms;
}

// The sessions' counters, the TCP port's or the WebSocket's.
nlohmann::json session_counters(const server::ServerStats& s) {
  return {{"sessions_opened", s.sessions_opened.load()},
          {"sessions_active", s.sessions_active.load()},
          {"sessions_refused", s.sessions_refused.load()},
          {"sessions_timed_out", s.sessions_timed_out.load()},
          {"sessions_failed", s.sessions_failed.load()},
          {"protocol_errors", s.protocol_errors.load()},
          {"accept_failures", s.accept_failures.load()},
          {"longest_turn_us", s.longest_turn_us.load()},
          {"bytes_in", s.bytes_in.load()},
          {"bytes_out", s.bytes_out.load()},
          {"splits_sent", s.splits_sent.load()},
          {"errors_sent", s.errors_sent.load()},
          {"peak_state_bytes", s.peak_state_bytes.load()},
          {"peak_buffer_bytes", s.peak_buffer_bytes.load()},
          {"fronts_parked", s.fronts_parked.load()}};
}

// One line a program can read: the event, then every counter (docs/operating.md lists them).
nlohmann::json stats_json(const char* event, const server::ServerStats& s, const Stopwatch& uptime) {
  // The kernel syncs a thread's RSS count into VmHWM lazily (pages at a time), so VmHWM read now can be
  // below a VmRSS printed earlier: the peak printed is never below any RSS this server printed.
  // Only the thread that waits for signals prints these lines.
  static uint64_t highest_rss = 0;
  const uint64_t rss = rss_bytes();
  highest_rss = std::max(highest_rss, rss);
  const uint64_t peak_rss = std::max(uint64_t(peak_rss_mb() * 1024 * 1024), highest_rss);
  nlohmann::json line = session_counters(s);
  line["event"] = event;
  line["uptime_s"] = uptime.seconds();
  line["rss_bytes"] = rss;
  line["peak_rss_bytes"] = peak_rss;
  line["cpu_s"] = cpu_seconds();
  line["phases_ms"] = phase_ms(s.phases);
  return line;
}

// The tables built so far, per model and mode, and the builders' counters (docs/operating.md, "Tables").
void add_table_stats(nlohmann::json& line, const server::Catalogue& catalogue) {
  using State = server::ModelTables::State;
  static constexpr const char* kStates[] = {"absent", "queued", "building", "ready", "failed"};
  nlohmann::json tables = nlohmann::json::array();
  for (const auto& model : catalogue.models())
    for (size_t m = 0; m < server::kServedModeCount; ++m) {
      const server::ServedMode mode = server::served_mode_at(m);
      const State state = model->tables->state(mode);
      if (state == State::absent) continue;
      tables.push_back({{"model", model->name},
                        {"mode", server::served_mode_name(mode)},
                        {"state", kStates[size_t(state)]},
                        {"bytes", model->tables->bytes(mode)}});
    }
  const server::TableBuildStats& s = catalogue.table_builds().stats();
  line["table_bytes"] = catalogue.table_bytes();
  line["tables"] = tables;
  line["table_builds_started"] = s.started.load();
  line["table_builds_failed"] = s.failed.load();
  line["table_builds_running"] = s.running.load();
  line["table_builds_peak"] = s.peak_running.load();
  line["table_waits"] = s.waits.load();
}

void add_http_stats(nlohmann::json& line, const server::HttpServer& http, const server::HttpLimits& limits) {
  const server::HttpStats& s = http.stats();
  line["http"] = {{"connections_opened", s.connections_opened.load()},
                  {"connections_active", s.connections_active.load()},
                  {"connections_refused", s.connections_refused.load()},
                  {"connections_refused_per_address", s.connections_refused_per_address.load()},
                  {"connections_timed_out", s.connections_timed_out.load()},
                  {"connections_reset", s.connections_reset.load()},
                  {"addresses_tracked", http.tracked_addresses()},
                  {"budget_waits", s.budget_waits.load()},
                  {"sliced_answers", s.sliced_answers.load()},
                  {"longest_turn_us", s.longest_turn_us.load()},
                  {"socket_buffer_bound_bytes", server::http_socket_buffer_bound(limits)},
                  {"requests", s.requests.load()},
                  {"not_modified", s.not_modified.load()},
                  {"client_errors", s.client_errors.load()},
                  {"bytes_in", s.bytes_in.load()},
                  {"bytes_out", s.bytes_out.load()},
                  {"splits_served", s.splits_served.load()},
                  {"split_requests", s.split_requests.load()},
                  {"phases_ms", phase_ms(s.phases)}};
  const server::WsStats& ws = http.ws_stats();
  nlohmann::json& counters = line["ws"] = session_counters(http.ws_sessions());
  counters["upgrades"] = ws.upgrades.load();
  counters["refused_origin"] = ws.refused_origin.load();
  counters["refused_full"] = ws.refused_full.load();
  counters["refused_malformed"] = ws.refused_malformed.load();
  counters["messages_refused"] = ws.messages_refused.load();
  counters["budget_waits"] = ws.budget_waits.load();
}

void print_line(const std::string& line) {
  std::printf("%s\n", line.c_str());
  std::fflush(stdout);
}

// `event` starts the line: "stats" for the totals so far (SIGUSR1), "stopped" for the last ones.
void print_totals(const char* event, const server::ServerStats& s) {
  std::printf(
      "%s: %llu sessions (%llu refused, %llu timed out, %llu failed), %llu protocol errors, "
      "%llu bytes in, %llu bytes out, %llu vsplits sent, "
      "peak session state %llu bytes (%llu without its active tags), peak RSS %.0f MB\n",
      event, (unsigned long long)s.sessions_opened.load(), (unsigned long long)s.sessions_refused.load(),
      (unsigned long long)s.sessions_timed_out.load(), (unsigned long long)s.sessions_failed.load(),
      (unsigned long long)s.protocol_errors.load(), (unsigned long long)s.bytes_in.load(),
      (unsigned long long)s.bytes_out.load(), (unsigned long long)s.splits_sent.load(),
      (unsigned long long)s.peak_state_bytes.load(), (unsigned long long)s.peak_buffer_bytes.load(), peak_rss_mb());
  std::fflush(stdout);
}

void print_stats(const char* event, const ServeArgs& args, const server::Catalogue& catalogue,
                 const server::TcpServer& tcp, const server::HttpServer* http, const Stopwatch& uptime,
                 const ReloadCounts& reloads) {
  if (args.json) {
    nlohmann::json line = stats_json(event, tcp.stats(), uptime);
    add_table_stats(line, catalogue);
    line.update(reload_stats(reloads));
    if (http) add_http_stats(line, *http, args.http);
    print_line(line.dump());
  } else {
    print_totals(event, tcp.stats());
    std::printf("tables: %llu bytes built\n", (unsigned long long)catalogue.table_bytes());
    if (reloads.reloads > 0)
      std::printf("reloads: %llu (%llu failed): %llu models added, %llu removed, %llu replaced, %llu files skipped\n",
                  (unsigned long long)reloads.reloads, (unsigned long long)reloads.failed,
                  (unsigned long long)reloads.added, (unsigned long long)reloads.removed,
                  (unsigned long long)reloads.replaced, (unsigned long long)reloads.skipped);
    if (http) {
      const server::HttpStats& s = http->stats();
      std::printf(
          "http: %llu connections (%llu refused, %llu timed out), %llu requests (%llu not modified, "
          "%llu client errors), %llu bytes in, %llu bytes out, %llu splits served in %llu split requests\n",
          (unsigned long long)s.connections_opened.load(), (unsigned long long)s.connections_refused.load(),
          (unsigned long long)s.connections_timed_out.load(), (unsigned long long)s.requests.load(),
          (unsigned long long)s.not_modified.load(), (unsigned long long)s.client_errors.load(),
          (unsigned long long)s.bytes_in.load(), (unsigned long long)s.bytes_out.load(),
          (unsigned long long)s.splits_served.load(), (unsigned long long)s.split_requests.load());
      const server::ServerStats& w = http->ws_sessions();
      std::printf("ws: %llu sessions (%llu refused, %llu timed out), %llu upgrades refused (origin %llu), %llu bytes "
                  "in, %llu bytes out\n",
                  (unsigned long long)w.sessions_opened.load(), (unsigned long long)w.sessions_refused.load(),
                  (unsigned long long)w.sessions_timed_out.load(),
                  (unsigned long long)(http->ws_stats().refused_origin.load() + http->ws_stats().refused_full.load() +
                                       http->ws_stats().refused_malformed.load()),
                  (unsigned long long)http->ws_stats().refused_origin.load(), (unsigned long long)w.bytes_in.load(),
                  (unsigned long long)w.bytes_out.load());
      std::fflush(stdout);
    }
  }
}

void run_serve(ServeArgs args) {
  // Signals go to the thread that waits for them, not to an I/O thread.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGUSR1);
  sigaddset(&signals, SIGHUP);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);

  const Stopwatch uptime;
  server::TableOptions tables;
  if (args.preload_given) tables.preload = server::parse_modes(args.preload, "--preload");
  else tables.preload.reset();
  tables.max_builds = args.max_table_builds;
  const auto catalogue = server::Catalogue::open(args.paths, args.limits.position_bits, tables);
  const auto catalogues = std::make_shared<server::CatalogueSlot>(catalogue);
  server::TcpServer tcp(catalogues, args.limits, args.host, args.port);
  std::unique_ptr<server::HttpServer> http;
  if (args.http_port_given) {
    args.http.threads = args.limits.threads;
    if (args.web.root.empty()) args.web.root = default_web_root();
    args.web.sessions = args.limits;
    http = std::make_unique<server::HttpServer>(catalogues, args.http, args.host, args.http_port, args.web);
  }
  tcp.start();
  if (http) http->start();
  if (args.json) {
    nlohmann::json models = nlohmann::json::array();
    for (const auto& model : catalogue->models())
      models.push_back({{"name", model->name},
                        {"version", model->version},
                        {"path", model->path},
                        {"faces", model->info.input_faces},
                        {"base_vertices", model->info.base_vertices},
                        {"vsplits", model->info.vsplits}});
    nlohmann::json line{{"event", "listening"}, {"host", args.host}, {"port", tcp.port()}, {"models", models}};
    if (http) line["http_port"] = http->port();
    line["rss_bytes"] = rss_bytes();
    add_table_stats(line, *catalogue);
    print_line(line.dump());
  } else {
    for (const auto& model : catalogue->models())
      std::printf("serving %s: %llu faces, %u base vertices, %llu vsplits (%s)\n", model->name.c_str(),
                  (unsigned long long)model->info.input_faces, model->info.base_vertices,
                  (unsigned long long)model->info.vsplits, model->path.c_str());
    print_line("listening on " + args.host + ":" + std::to_string(tcp.port()) +
               " (TCP, sender-driven); Ctrl-C stops, SIGUSR1 prints the totals so far, SIGHUP reloads the models");
    if (http)
      print_line("listening on " + args.host + ":" + std::to_string(http->port()) +
                 " (HTTP: the page at /, receiver-driven and multilevel under /models, the session modes' WebSocket "
                 "at /ws)");
  }
  ReloadCounts reloads;
  for (;;) {
    int received = 0;
    sigwait(&signals, &received);
    if (received == SIGHUP) reload_models(*catalogues, args.limits, args.json, reloads);
    else if (received == SIGUSR1) print_stats("stats", args, *catalogues->get(), tcp, http.get(), uptime, reloads);
    else break;
  }
  if (http) http->stop();
  tcp.stop();
  print_stats("stopped", args, *catalogues->get(), tcp, http.get(), uptime, reloads);
}

CliOption add_limit(CliCommand& cmd, const char* name, uint32_t& value, const char* help) {
  return cmd.option(name, value, help).show_default();
}

}  // namespace

void add_serve_command(CliCommand& app) {
  auto args = std::make_shared<ServeArgs>();
  server::ServerLimits& limits = args->limits;
  CliCommand cmd = app.subcommand(
      "serve",
      "Serve .pms models to streaming clients (sender-driven over TCP; with --http-port, receiver-driven over HTTP, "
      "the browser page and a WebSocket for the session modes)");
  cmd.option("paths", args->paths, ".pms files or directories holding them").required();
  cmd.option("--host", args->host, "Address to listen on").show_default();
  cmd.option("--port", args->port, "TCP port (0: any free port, printed at start)").show_default();
  const CliOption http_port =
      cmd.option("--http-port", args->http_port,
                 "Also serve the receiver-driven mode over HTTP on this port (0: any free port, printed at start)");
  server::HttpLimits& http = args->http;
  // The HTTP limits, which only a server with --http-port uses.
  std::vector<VariantOption> http_only;
  const auto add_http_limit = [&](const char* name, uint32_t& value, const char* help) {
    http_only.push_back({add_limit(cmd, name, value, help), {"--http-port"}});
  };
  add_http_limit("--http-max-connections", http.max_connections, "Concurrent HTTP connections; more get 503");
  add_http_limit("--http-idle-timeout-ms", http.idle_timeout_ms,
                 "Close a keep-alive HTTP connection that begins no request for this long");
  add_http_limit("--http-request-timeout-ms", http.request_timeout_ms,
                 "An HTTP request, once begun, must arrive whole within this");
  add_http_limit("--http-write-timeout-ms", http.write_timeout_ms,
                 "Close an HTTP peer that takes no answer byte for this long");
  add_http_limit("--http-max-url-bytes", http.max_target_bytes,
                 "Longest request URL (414 over it; POST takes longer codes)");
  add_http_limit("--http-max-header-bytes", http.max_header_bytes,
                 "The request line (414 over it) and the header fields (431), each");
  add_http_limit("--http-max-body-bytes", http.max_body_bytes, "A POSTed request code (413 over it)");
  add_http_limit("--http-max-request-ids", http.max_request_ids, "Ids one request code may name (413 over it)");
  add_http_limit("--http-max-request-depth", http.max_request_depth,
                 "Descendant depth one request may ask for (400 over it)");
  add_http_limit("--http-max-response-splits", http.max_response_splits,
                 "Split records one answer may carry, descendants included (413 over it)");
  add_http_limit("--http-max-connections-per-address", http.max_connections_per_address,
                 "Concurrent HTTP connections from one client address; more get 503 (0 = no limit)");
  add_http_limit("--http-address-budget", http.address_budget,
                 "Work units a second one client address may take, bursts of as many; more wait, unread (0 = no "
                 "limit; a unit is about one split record encoded)");
  add_http_limit("--http-connection-budget", http.connection_budget,
                 "Work units a second one HTTP connection may take, bursts of as many; more wait, unread (0 = no "
                 "limit)");
  add_http_limit("--http-turn-us", http.turn_us,
                 "One HTTP connection's turn on an I/O thread, in microseconds; a larger answer is built over turns");
  add_http_limit("--http-send-buffer-bytes", http.send_buffer_bytes,
                 "Kernel send buffer asked per HTTP connection (SO_SNDBUF; Linux holds twice this)");
  add_http_limit("--http-receive-buffer-bytes", http.receive_buffer_bytes,
                 "Kernel receive buffer asked per HTTP connection (SO_RCVBUF; Linux holds twice this)");
  add_http_limit("--catalogue-max-age", http.catalogue_max_age_s,
                 "Seconds a cache may answer GET /models without asking again (then revalidated with its ETag); a "
                 "model added or replaced shows behind a cache within this (0: asked each time)");
  http_only.push_back({cmd.option("--trusted-proxy", args->trusted_proxies,
                                  "Peers (addresses or CIDR ranges) whose X-Forwarded-For names the client the "
                                  "per-address limits apply to, e.g. the nginx cache in front"),
                       {"--http-port"}});
  http_only.push_back({cmd.option("--web-root", args->web.root,
                                  "Directory of the page served at / on the HTTP port (default: web/ beside the "
                                  "pmstream executable)"),
                       {"--http-port"}});
  http_only.push_back({cmd.option("--ws-allowed-origin", args->web.allowed_origins,
                                  "Origins (scheme://host[:port]) a browser may open the WebSocket /ws from "
                                  "(default: the page's own origin only)"),
                       {"--http-port"}});
  cmd.flag("--json", args->json, "Print one JSON object per line: listening, stats (SIGUSR1), stopped");
  add_limit(cmd, "--max-sessions", limits.max_sessions, "Concurrent sessions; more are refused (server_full)");
  add_limit(cmd, "--threads", limits.threads, "I/O threads (0 = one per core)");
  add_limit(cmd, "--idle-timeout-ms", limits.idle_timeout_ms,
            "Close a session that sends nothing and takes no answer byte for this long");
  add_limit(cmd, "--handshake-timeout-ms", limits.handshake_timeout_ms,
            "Close a connection that has not said HELLO and OPEN within this");
  add_limit(cmd, "--frame-timeout-ms", limits.frame_timeout_ms, "A message, once begun, must arrive whole within this");
  add_limit(cmd, "--write-timeout-ms", limits.write_timeout_ms,
            "Close a peer that leaves answer bytes waiting and takes none for this long");
  add_limit(cmd, "--accept-backoff-ms", limits.accept_backoff_ms,
            "Longest pause after a failed accept (out of file descriptors), doubling from 10 ms");
  add_limit(cmd, "--turn-us", limits.turn_us, "One session's turn on an I/O thread, in microseconds");
  add_limit(cmd, "--max-message-rate", limits.max_message_rate,
            "Messages per second a session may send (bursts of as many); more wait, unread (0 = no limit)");
  add_limit(cmd, "--max-client-message", limits.max_client_message,
            "Largest message payload a client may send (bytes)");
  add_limit(cmd, "--max-server-message", limits.max_server_message,
            "Largest message payload the server sends (bytes); a model whose BASE is larger is refused at start");
  cmd.option("--send-queue-bytes", limits.send_queue_bytes,
             "Answer bytes queued per session before it waits for the peer to read")
      .show_default();
  cmd.option("--batch", limits.batch_splits, "vsplit packets per VSPLITS message")
      .range(1u, protocol::kMaxPacketsPerMessage)
      .show_default();
  add_limit(cmd, "--position-bits", limits.position_bits, "Bits per coordinate on the wire (1-24, or 32)");
  cmd.option("--session-front", args->session_front,
             "How a sender-driven session holds its client's front between VIEWs: compact (about two bits a node) "
             "or tags (the paper's windowed active tags)")
      .one_of({"compact", "tags"})
      .show_default();
  add_limit(cmd, "--park-after-ms", limits.park_after_ms,
            "A sender-driven session with no message for this long codes its front compact (0 = after every "
            "answer; a flying client sends a VIEW a frame and keeps its tags)");
  add_limit(cmd, "--ahead-budget", limits.ahead_budget_bytes,
            "Bytes a sender-driven session may send ahead of its views while idle (AHEAD, stream --ahead) over "
            "its life, at most one batch over; 0 = none");
  cmd.flag("--profile-phases", limits.profile_phases,
           "Time the sessions' and the HTTP answers' work by cheng-ooi's Table 1 phases (stats lines: phases_ms)");
  const CliOption preload =
      cmd.option("--preload", args->preload,
                 "Build these modes' tables before listening: all, or a comma list of sender, sender-plain, vi, dag, "
                 "receiver, multilevel (default: each when a client first asks for it)");
  cmd.option("--max-table-builds", args->max_table_builds, "Table builds running at once; more wait in a queue")
      .range(1u, 64u)
      .show_default();
  cmd.on_run([args, http_port, preload, http_only] {
    args->http_port_given = http_port.given();
    if (!args->http_port_given) refuse_unused_options(http_only, "", "serve without --http-port");
    args->http.trusted_proxies = server::AddressRanges::parse(args->trusted_proxies, "--trusted-proxy");
    args->preload_given = preload.given();
    args->limits.compact_fronts = args->session_front == "compact";
    args->http.profile_phases = args->limits.profile_phases;
    run_serve(*args);
  });
}

}  // namespace pms::app
