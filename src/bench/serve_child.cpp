#include "bench/serve_child.h"

#include <signal.h>

#include "common/error.h"

namespace pms::bench {
using nlohmann::json;
namespace {

uint64_t counter(const json& line, const char* name) {
  const auto it = line.find(name);
  // A parsed count is unsigned; one built in code may be a signed integer: either, if not negative.
  if (it == line.end() || !it->is_number_integer() || (!it->is_number_unsigned() && it->get<int64_t>() < 0))
    fail("serve",
         std::string("the \"") + line.value("event", "?") + "\" line has no counter " + name + ": " + line.dump());
  return it->get<uint64_t>();
}

double seconds(const json& line, const char* name) {
  const auto it = line.find(name);
  if (it == line.end() || !it->is_number())
    fail("serve", std::string("the \"") + line.value("event", "?") + "\" line has no " + name + ": " + line.dump());
  return it->get<double>();
}

}  // namespace

ServeStats parse_serve_stats(const json& line) {
  ServeStats s;
  s.uptime_s = seconds(line, "uptime_s");
  s.cpu_s = seconds(line, "cpu_s");
  s.sessions_opened = counter(line, "sessions_opened");
  s.sessions_active = counter(line, "sessions_active");
  s.sessions_refused = counter(line, "sessions_refused");
  s.sessions_timed_out = counter(line, "sessions_timed_out");
  s.sessions_failed = counter(line, "sessions_failed");
  s.protocol_errors = counter(line, "protocol_errors");
  s.accept_failures = counter(line, "accept_failures");
  s.longest_turn_us = counter(line, "longest_turn_us");
  s.bytes_in = counter(line, "bytes_in");
  s.bytes_out = counter(line, "bytes_out");
  s.splits_sent = counter(line, "splits_sent");
  s.errors_sent = counter(line, "errors_sent");
  s.peak_state_bytes = counter(line, "peak_state_bytes");
  s.peak_buffer_bytes = counter(line, "peak_buffer_bytes");
  s.rss_bytes = counter(line, "rss_bytes");
  s.peak_rss_bytes = counter(line, "peak_rss_bytes");
  s.line = line;
  return s;
}

namespace {

std::vector<std::string> serve_argv(const std::string& pmstream_exe, const std::vector<std::string>& args,
                                    uint16_t port) {
  std::vector<std::string> argv = {pmstream_exe, "serve"};
  argv.insert(argv.end(), args.begin(), args.end());
  for (const char* arg : {"--json", "--host", "127.0.0.1", "--port"}) argv.push_back(arg);
  argv.push_back(std::to_string(port));
  return argv;
}

}  // namespace

ServeChild::ServeChild(const std::string& pmstream_exe, const std::vector<std::string>& args, double start_timeout_s,
                       uint16_t port)
    : child_("serve", serve_argv(pmstream_exe, args, port)) {
  try {
    listening_ = child_.next_line("listening", start_timeout_s);
    const auto found = listening_.find("port");
    if (found == listening_.end() || !found->is_number_unsigned() || *found == 0 || *found > 65535)
      fail("serve", "the \"listening\" line has no port: " + listening_.dump());
    port_ = found->get<uint16_t>();
  } catch (...) {
    child_.kill();
    throw;
  }
}

ServeStats ServeChild::stats(double timeout_s) {
  child_.send_signal(SIGUSR1, "SIGUSR1");
  return parse_serve_stats(child_.next_line("stats", timeout_s));
}

json ServeChild::reload(double timeout_s) {
  child_.send_signal(SIGHUP, "SIGHUP");
  return child_.next_line("reloaded", timeout_s);
}

ServeStats ServeChild::stop(double timeout_s) {
  child_.send_signal(SIGTERM, "SIGTERM");
  const ServeStats stopped = parse_serve_stats(child_.next_line("stopped", timeout_s));
  child_.wait_ok(timeout_s);
  return stopped;
}

}  // namespace pms::bench
