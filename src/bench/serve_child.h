// `pmstream serve --json` as a child process, read a line at a time: the benches' only view of a
// server's counters (docs/operating.md lists them). A line that is missing, unparsable or lacks a
// counter is a pms::Error naming what was expected, never a silent 0.
#pragma once
#include <sys/types.h>

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "bench/line_child.h"

namespace pms::bench {

// One "stats" or "stopped" line.
struct ServeStats {
  double uptime_s = 0, cpu_s = 0;
  uint64_t sessions_opened = 0, sessions_active = 0, sessions_refused = 0, sessions_timed_out = 0;
  uint64_t sessions_failed = 0, protocol_errors = 0, accept_failures = 0, longest_turn_us = 0;
  uint64_t bytes_in = 0, bytes_out = 0, splits_sent = 0, errors_sent = 0;
  uint64_t peak_state_bytes = 0, peak_buffer_bytes = 0;
  uint64_t rss_bytes = 0, peak_rss_bytes = 0;
  nlohmann::json line;  // as printed
};

// pms::Error naming the first counter that is absent or not a number.
ServeStats parse_serve_stats(const nlohmann::json& line);

class ServeChild {
 public:
  // Runs `pmstream_exe serve ARGS... --json --host 127.0.0.1 --port PORT` and waits for its "listening"
  // line (with port 0, the port the kernel picked is in it, so nothing has to guess a free one). A given
  // port brings a server back where a proxy in front of it expects it.
  ServeChild(const std::string& pmstream_exe, const std::vector<std::string>& args, double start_timeout_s = 120,
             uint16_t port = 0);
  // A server still running when it is destroyed is killed (SIGKILL).
  uint16_t port() const { return port_; }
  pid_t pid() const { return child_.pid(); }  // for /proc; 0 before it started
  const nlohmann::json& listening() const { return listening_; }
  // SIGUSR1, then the "stats" line it prints.
  ServeStats stats(double timeout_s = 30);
  // SIGHUP, then the "reloaded" line: what the reload added, removed, replaced and skipped.
  nlohmann::json reload(double timeout_s = 60);
  // SIGTERM, then the "stopped" line; the server must then exit with status 0.
  ServeStats stop(double timeout_s = 30);
  // What it wrote to stderr (one line per session fault); read it only after stop() returned.
  const std::string& log() const { return child_.log(); }

 private:
  LineChild child_;
  nlohmann::json listening_;
  uint16_t port_ = 0;
};

}  // namespace pms::bench
