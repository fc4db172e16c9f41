#include "bench/haproxy_child.h"

#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <sstream>
#include <system_error>
#include <thread>

#include "common/error.h"

namespace pms::bench {
namespace fs = std::filesystem;
namespace {

const char* const kBackends[] = {"pmstream_sessions", "pmstream_http"};
constexpr int kRuntimeApiTimeoutMs = 5000;

std::string loopback(uint16_t port) { return "127.0.0.1:" + std::to_string(port); }

// The CSV line's fields (`show stat` quotes nothing).
std::vector<std::string> fields(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream in(line);
  for (std::string field; std::getline(in, field, ',');) out.push_back(field);
  return out;
}

}  // namespace

HaproxyChild::SocketDirectory::SocketDirectory() {
  char name[] = "/tmp/pmstream-haproxy-XXXXXX";
  if (!::mkdtemp(name)) fail("haproxy", std::string("mkdtemp: ") + std::strerror(errno));
  path = name;
}

HaproxyChild::SocketDirectory::~SocketDirectory() {
  std::error_code ignored;
  fs::remove_all(path, ignored);
}

HaproxyChild::HaproxyChild(const std::string& program, const fs::path& config,
                           const std::vector<HaproxyOrigin>& origins)
    : socket_(socket_dir_.path / "api.sock"), daemon_("haproxy", [&] { return prepare(program, config, origins); }) {}

DaemonStart HaproxyChild::prepare(const std::string& program, const fs::path& config,
                                  const std::vector<HaproxyOrigin>& origins) {
  if (origins.size() != 2)
    fail("haproxy", "the configuration names two origins, not " + std::to_string(origins.size()));
  session_port_ = free_loopback_port();
  http_port_ = free_loopback_port();
  std::vector<std::string> env = {"PMSTREAM_SESSIONS_BIND=" + loopback(session_port_),
                                  "PMSTREAM_HTTP_BIND=" + loopback(http_port_),
                                  "PMSTREAM_HAPROXY_SOCKET=" + socket_.string()};
  for (size_t i = 0; i < origins.size(); ++i) {
    const std::string name = "PMSTREAM_ORIGIN" + std::to_string(i + 1);
    env.push_back(name + "_SESSIONS=" + loopback(origins[i].session_port));
    env.push_back(name + "_HTTP=" + loopback(origins[i].http_port));
  }
  // -db: in the foreground, as under systemd's Type=notify; stopped by SIGTERM (hard stop).
  return {{program, "-db", "-f", config.string()}, env, session_port_};
}

// One command over the stats socket, its whole answer (HAProxy closes after answering).
std::string HaproxyChild::runtime_api(const std::string& command) const {
  const int fd = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) fail("haproxy", std::string("runtime API: socket: ") + std::strerror(errno));
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  std::strncpy(address.sun_path, socket_.c_str(), sizeof address.sun_path - 1);
  std::string answer;
  const std::string line = command + "\n";
  bool ok = ::connect(fd, reinterpret_cast<const sockaddr*>(&address), sizeof address) == 0 &&
            ::write(fd, line.data(), line.size()) == ssize_t(line.size());
  for (char buffer[4096]; ok;) {
    pollfd ready{fd, POLLIN, 0};
    ok = ::poll(&ready, 1, kRuntimeApiTimeoutMs) == 1;
    const ssize_t got = ok ? ::read(fd, buffer, sizeof buffer) : -1;
    if (got <= 0) break;
    answer.append(buffer, size_t(got));
  }
  const int error = errno;
  ::close(fd);
  if (!ok) fail("haproxy", "runtime API at " + socket_.string() + ": " + std::strerror(error));
  return answer;
}

std::string HaproxyChild::stat(const std::string& backend, const std::string& server, const std::string& field) const {
  std::stringstream table(runtime_api("show stat"));
  std::string line;
  std::getline(table, line);  // "# pxname,svname,...,status,..."
  if (line.rfind("# ", 0) != 0) fail("haproxy", "`show stat` answered: " + line);
  const std::vector<std::string> header = fields(line.substr(2));
  size_t column = 0;
  while (column < header.size() && header[column] != field) ++column;
  while (std::getline(table, line)) {
    const std::vector<std::string> row = fields(line);
    if (row.size() > column && row[0] == backend && row[1] == server) return row[column];
  }
  fail("haproxy", "`show stat` has no " + field + " of server " + server + " in " + backend);
}

std::string HaproxyChild::status(const std::string& backend, const std::string& server) const {
  return stat(backend, server, "status");
}

bool HaproxyChild::await_state(const std::string& server, const std::string& state,
                               std::chrono::milliseconds deadline) const {
  const auto until = std::chrono::steady_clock::now() + deadline;
  for (;;) {
    bool all = true;
    try {
      for (const char* backend : kBackends) all = all && status(backend, server) == state;
    } catch (const Error&) {
      all = false;  // HAProxy takes its port before its runtime API's socket: ask again
    }
    if (all) return true;
    if (std::chrono::steady_clock::now() >= until) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
}

}  // namespace pms::bench
