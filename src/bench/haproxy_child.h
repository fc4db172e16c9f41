// Debian's HAProxy on loopback with the repo's deploy/haproxy/pmstream.cfg, the file users run, in front of
// two `pmstream serve` origins: its addresses go in through the environment the file reads ("${NAME}"),
// so nothing is rewritten. The failover test and the bench's failover figure run it.
#pragma once
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "bench/loopback_daemon.h"

namespace pms::bench {

// One origin's two ports as `serve --port --http-port` took them.
struct HaproxyOrigin {
  uint16_t session_port = 0, http_port = 0;
};

class HaproxyChild {
 public:
  // `origins`: exactly the two the file names (origin1, origin2).
  HaproxyChild(const std::string& program, const std::filesystem::path& config,
               const std::vector<HaproxyOrigin>& origins);
  HaproxyChild(const HaproxyChild&) = delete;
  HaproxyChild& operator=(const HaproxyChild&) = delete;

  uint16_t session_port() const { return session_port_; }  // the sender-driven protocol, balanced
  uint16_t http_port() const { return http_port_; }        // the HTTP port, /ws included

  // An origin's state in a backend ("pmstream_sessions", "pmstream_http") as the runtime API's `show stat`
  // says it: "UP", "DOWN", "UP 1/2" (going down), "DOWN 1/2" (coming up), ...; pms::Error when HAProxy
  // does not answer or lists no such server.
  std::string status(const std::string& backend, const std::string& server) const;
  // Waits until the origin's state in every backend is exactly `state` ("UP", "DOWN"); false at the deadline.
  bool await_state(const std::string& server, const std::string& state, std::chrono::milliseconds deadline) const;

 private:
  std::string runtime_api(const std::string& command) const;
  // One field of a server's row in `show stat`.
  std::string stat(const std::string& backend, const std::string& server, const std::string& field) const;
  DaemonStart prepare(const std::string& program, const std::filesystem::path& config,
                      const std::vector<HaproxyOrigin>& origins);

  // The runtime API's socket, in a directory of its own under /tmp (a socket's path has at most 107 bytes,
  // fewer than a test's temporary directory may take), removed with it.
  struct SocketDirectory {
    SocketDirectory();
    ~SocketDirectory();
    std::filesystem::path path;
  };
  SocketDirectory socket_dir_;
  std::filesystem::path socket_;
  uint16_t session_port_ = 0, http_port_ = 0;
  LoopbackDaemon daemon_;  // last: prepare() fills the members above
};

}  // namespace pms::bench
