// pmstream serve FILES_OR_DIRS... [--port 7300] [--host 0.0.0.0] [--max-sessions N] ...
// Runs the sender-driven TCP server until SIGINT or SIGTERM.
#include <csignal>
#include <cstdio>
#include <pthread.h>

#include "apps/commands.h"
#include "apps/resource_usage.h"
#include "common/error.h"
#include "server/server.h"

namespace pms::app {
namespace {

struct ServeArgs {
  std::vector<std::string> paths;
  std::string host = "0.0.0.0";
  uint16_t port = 7300;
  uint16_t http_port = 0;
  server::ServerLimits limits;
};

void run_serve(const ServeArgs& args) {
  if (args.http_port != 0)
    fail("serve", "--http-port: the HTTP/WebSocket transport (receiver-driven mode, browser) is not in this build yet");
  // Signals go to the thread that waits for them, not to an I/O thread.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);

  const auto catalogue = server::Catalogue::open(args.paths, args.limits.position_bits);
  server::TcpServer tcp(catalogue, args.limits, args.host, args.port);
  tcp.start();
  for (const auto& model : catalogue->models())
    std::printf("serving %s: %llu faces, %u base vertices, %llu vsplits (%s)\n", model->name.c_str(),
                (unsigned long long)model->info.input_faces, model->info.base_vertices,
                (unsigned long long)model->info.vsplits, model->path.c_str());
  std::printf("listening on %s:%u (TCP, sender-driven); Ctrl-C stops\n", args.host.c_str(), unsigned(tcp.port()));
  std::fflush(stdout);
  int received = 0;
  sigwait(&signals, &received);
  tcp.stop();
  const server::ServerStats& s = tcp.stats();
  std::printf("stopped: %llu sessions (%llu refused), %llu bytes in, %llu bytes out, %llu vsplits sent, "
              "peak session state %llu bytes (%llu without its active tags), peak RSS %.0f MB\n",
              (unsigned long long)s.sessions_opened.load(), (unsigned long long)s.sessions_rejected.load(),
              (unsigned long long)s.bytes_in.load(), (unsigned long long)s.bytes_out.load(),
              (unsigned long long)s.splits_sent.load(), (unsigned long long)s.peak_state_bytes.load(),
              (unsigned long long)s.peak_buffer_bytes.load(), peak_rss_mb());
}

}  // namespace

void add_serve_command(CLI::App& app) {
  auto args = std::make_shared<ServeArgs>();
  CLI::App* cmd = app.add_subcommand("serve", "Serve .pms models to streaming clients (sender-driven, TCP)");
  cmd->add_option("paths", args->paths, ".pms files or directories holding them")->required();
  cmd->add_option("--host", args->host, "Address to listen on")->capture_default_str();
  cmd->add_option("--port", args->port, "TCP port")->capture_default_str();
  cmd->add_option("--http-port", args->http_port, "HTTP + WebSocket port (receiver-driven mode; later)");
  cmd->add_option("--max-sessions", args->limits.max_sessions, "Concurrent sessions")->capture_default_str();
  cmd->add_option("--threads", args->limits.threads, "I/O threads (0 = one per core)")->capture_default_str();
  cmd->add_option("--idle-timeout-ms", args->limits.idle_timeout_ms, "Close a silent session after this")
      ->capture_default_str();
  cmd->add_option("--batch", args->limits.batch_splits, "vsplit packets per VSPLITS message")
      ->check(CLI::Range(1u, 1u << 16))
      ->capture_default_str();
  cmd->add_option("--position-bits", args->limits.position_bits, "Bits per coordinate on the wire (1-24, or 32)")
      ->capture_default_str();
  cmd->callback([args] { run_serve(*args); });
}

}  // namespace pms::app
