// Debian's nginx on loopback with the repo's deploy/nginx/pmstream-cache.conf, the file users run, in front
// of one or more `pmstream serve` origins: the template's @NAMES@ filled in as docs/operating.md tells an
// operator to (one `server` line per origin), in a directory of its own that holds its pid, logs, temporary
// files and cache. The cache tests and the bench's tier figure run it.
#pragma once
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "bench/loopback_daemon.h"

namespace pms::bench {

// The template `conf` with `dir`, `listen` and the origins' addresses ("127.0.0.1:7301") filled in: the
// @ORIGIN1@ `server` line once per origin, the other @ORIGINn@ lines dropped. pms::Error when the template
// has no @ORIGIN1@ line or no origin is given.
std::string nginx_config(std::string conf, const std::string& user, const std::filesystem::path& dir,
                         const std::string& listen, const std::vector<std::string>& origins);

// One line of the access log (the file's log_format).
struct AccessLogLine {
  int status = 0;
  uint64_t body_bytes = 0;
  std::string cache;      // $upstream_cache_status: "HIT", "MISS", "EXPIRED", ...; "-" for none
  std::string upstreams;  // $upstream_addr: the origins tried in order, "A, B"; "-" for none
};
std::vector<AccessLogLine> read_access_log(const std::filesystem::path& log);

class NginxChild {
 public:
  // nginx in the foreground in `dir` (created if need be), in front of the HTTP ports `origin_ports` on
  // loopback; stopped (SIGTERM, nginx's fast shutdown) when destroyed.
  NginxChild(const std::string& program, const std::filesystem::path& config, const std::filesystem::path& dir,
             const std::vector<uint16_t>& origin_ports);
  NginxChild(const NginxChild&) = delete;
  NginxChild& operator=(const NginxChild&) = delete;

  uint16_t port() const { return port_; }
  std::string url() const { return "http://127.0.0.1:" + std::to_string(port_); }
  // access.log: one line per request (the file's log_format: address, request, status, body bytes, cache
  // status, origin time).
  std::filesystem::path access_log() const { return dir_ / "access.log"; }

 private:
  DaemonStart prepare(const std::string& program, const std::filesystem::path& config,
                      const std::vector<uint16_t>& origin_ports);

  std::filesystem::path dir_;
  uint16_t port_ = 0;
  LoopbackDaemon daemon_;  // last: prepare() fills the members above
};

}  // namespace pms::bench
