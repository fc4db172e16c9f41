#include "bench/nginx_child.h"

#include <pwd.h>
#include <unistd.h>

#include <fstream>
#include <sstream>

#include "common/error.h"

namespace pms::bench {
namespace fs = std::filesystem;
namespace {

void replace_all(std::string& text, const std::string& name, const std::string& value) {
  for (size_t at = 0; (at = text.find(name, at)) != std::string::npos; at += value.size())
    text.replace(at, name.size(), value);
}

}  // namespace

std::string nginx_config(std::string conf, const std::string& user, const fs::path& dir, const std::string& listen,
                         const std::vector<std::string>& origins) {
  if (origins.empty()) fail("nginx", "a cache tier needs at least one origin");
  replace_all(conf, "@USER@", user);
  replace_all(conf, "@DIR@", dir.string());
  replace_all(conf, "@LISTEN@", listen);
  std::istringstream in(conf);
  std::string out, line;
  bool placed = false;
  while (std::getline(in, line)) {
    if (line.find("@ORIGIN") == std::string::npos) {
      out += line + "\n";
    } else if (line.find("@ORIGIN1@") != std::string::npos) {
      for (const std::string& origin : origins) {
        std::string server = line;
        replace_all(server, "@ORIGIN1@", origin);
        out += server + "\n";
      }
      placed = true;
    }
  }
  if (!placed) fail("nginx", "the configuration has no `server @ORIGIN1@` line");
  return out;
}

std::vector<AccessLogLine> read_access_log(const fs::path& log) {
  std::vector<AccessLogLine> lines;
  std::ifstream in(log);
  for (std::string text; std::getline(in, text);) {
    // ADDRESS "REQUEST" STATUS BYTES cache=STATUS origin=TIMES upstream=ADDRESSES: the request is the one
    // quoted field; the times and the addresses are lists when a request went to several origins.
    const size_t quote = text.rfind('"'), upstream = text.rfind(" upstream=");
    if (quote == std::string::npos || upstream == std::string::npos || upstream < quote) continue;
    std::istringstream rest(text.substr(quote + 1, upstream - quote - 1));
    AccessLogLine line;
    std::string cache;
    if (!(rest >> line.status >> line.body_bytes >> cache) || cache.rfind("cache=", 0) != 0) continue;
    line.cache = cache.substr(6);
    line.upstreams = text.substr(upstream + 10);
    lines.push_back(std::move(line));
  }
  return lines;
}

NginxChild::NginxChild(const std::string& program, const fs::path& config, const fs::path& dir,
                       const std::vector<uint16_t>& origin_ports)
    : dir_(dir), daemon_("nginx", [&] { return prepare(program, config, origin_ports); }, dir / "error.log") {}

DaemonStart NginxChild::prepare(const std::string& program, const fs::path& config,
                                const std::vector<uint16_t>& origin_ports) {
  fs::create_directories(dir_);
  port_ = free_loopback_port();
  std::vector<std::string> origins;
  for (uint16_t origin : origin_ports) origins.push_back("127.0.0.1:" + std::to_string(origin));
  const passwd* user = ::getpwuid(::geteuid());  // nginx ignores `user` unless it runs as root
  const std::string conf = nginx_config(file_text(config), user ? user->pw_name : "root", dir_,
                                        "127.0.0.1:" + std::to_string(port_), origins);
  const fs::path path = dir_ / "nginx.conf";
  std::ofstream(path) << conf;
  return {{program, "-p", dir_.string(), "-c", path.string(), "-e", (dir_ / "error.log").string(), "-g",
           "daemon off;"},
          {},
          port_};
}

}  // namespace pms::bench
