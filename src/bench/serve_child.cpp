#include "bench/serve_child.h"

#include <signal.h>

#include <cerrno>
#include <chrono>
#include <cstring>

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

ServeChild::ServeChild(const std::string& pmstream_exe, const std::vector<std::string>& args, double start_timeout_s,
                       uint16_t port) {
  std::vector<std::string> argv = {pmstream_exe, "serve"};
  argv.insert(argv.end(), args.begin(), args.end());
  for (const char* arg : {"--json", "--host", "127.0.0.1", "--port"}) argv.push_back(arg);
  argv.push_back(std::to_string(port));
  thread_ = std::thread([this, argv] {
    ChildOptions options;
    options.on_start = [this](pid_t pid) { pid_ = pid; };
    options.on_stdout = [this](std::string_view piece) {
      const std::lock_guard<std::mutex> lock(mutex_);
      partial_.append(piece);
      for (size_t newline; (newline = partial_.find('\n')) != std::string::npos; partial_.erase(0, newline + 1))
        lines_.push_back(partial_.substr(0, newline));
      changed_.notify_all();
    };
    ChildResult run;
    std::string error;
    try {
      run = run_child(argv, options);
    } catch (const Error& e) {
      error = e.what();
    }
    const std::lock_guard<std::mutex> lock(mutex_);
    run_ = std::move(run);
    start_error_ = error;
    exited_ = true;
    changed_.notify_all();
  });
  try {
    listening_ = next_line("listening", start_timeout_s);
    const auto port = listening_.find("port");
    if (port == listening_.end() || !port->is_number_unsigned() || *port == 0 || *port > 65535)
      fail("serve", "the \"listening\" line has no port: " + listening_.dump());
    port_ = port->get<uint16_t>();
  } catch (...) {
    if (pid_) ::kill(pid_, SIGKILL);
    thread_.join();
    throw;
  }
}

ServeChild::~ServeChild() {
  if (!thread_.joinable()) return;
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    if (!exited_ && pid_) ::kill(pid_, SIGKILL);
  }
  thread_.join();
}

json ServeChild::next_line(const std::string& event, double timeout_s) {
  std::unique_lock<std::mutex> lock(mutex_);
  const auto ready = [&] { return !lines_.empty() || exited_; };
  if (!changed_.wait_for(lock, std::chrono::duration<double>(timeout_s), ready))
    fail("serve", "no \"" + event + "\" line within " + std::to_string(int(timeout_s)) + " s");
  if (lines_.empty()) {
    const std::string why = !start_error_.empty() ? start_error_ : run_.ok() ? "exit code 0" : run_.failure();
    fail("serve", "ended (" + why + ") without its \"" + event + "\" line");
  }
  const std::string text = lines_.front();
  lines_.pop_front();
  const json line = json::parse(text, nullptr, false);
  if (line.is_discarded() || !line.is_object()) fail("serve", "a line that is not a JSON object: " + text);
  if (line.value("event", "") != event) fail("serve", "expected the \"" + event + "\" line, got: " + text);
  return line;
}

void ServeChild::send_signal(int number, const char* name) {
  const std::lock_guard<std::mutex> lock(mutex_);
  if (exited_ || !pid_) fail("serve", std::string("ended before ") + name + " could be sent");
  if (::kill(pid_, number) != 0) fail("serve", std::string("kill ") + name + ": " + std::strerror(errno));
}

ServeStats ServeChild::stats(double timeout_s) {
  send_signal(SIGUSR1, "SIGUSR1");
  return parse_serve_stats(next_line("stats", timeout_s));
}

json ServeChild::reload(double timeout_s) {
  send_signal(SIGHUP, "SIGHUP");
  return next_line("reloaded", timeout_s);
}

ServeStats ServeChild::stop(double timeout_s) {
  send_signal(SIGTERM, "SIGTERM");
  const ServeStats stopped = parse_serve_stats(next_line("stopped", timeout_s));
  {
    std::unique_lock<std::mutex> lock(mutex_);
    if (!changed_.wait_for(lock, std::chrono::duration<double>(timeout_s), [&] { return exited_; }))
      fail("serve", "still running " + std::to_string(int(timeout_s)) + " s after its \"stopped\" line");
  }
  thread_.join();
  if (!run_.ok()) fail("serve", "printed its \"stopped\" line, then " + run_.failure());
  return stopped;
}

}  // namespace pms::bench
