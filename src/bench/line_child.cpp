#include "bench/line_child.h"

#include <signal.h>

#include <cerrno>
#include <chrono>
#include <cstring>

#include "common/error.h"

namespace pms::bench {
using nlohmann::json;

LineChild::LineChild(std::string name, const std::vector<std::string>& argv) : name_(std::move(name)) {
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
}

LineChild::~LineChild() {
  if (!thread_.joinable()) return;
  kill();
  thread_.join();
}

void LineChild::kill() {
  const std::lock_guard<std::mutex> lock(mutex_);
  if (!exited_ && pid_) ::kill(pid_, SIGKILL);
}

json LineChild::next_line(const std::string& event, double timeout_s) {
  std::unique_lock<std::mutex> lock(mutex_);
  const auto ready = [&] { return !lines_.empty() || exited_; };
  if (!changed_.wait_for(lock, std::chrono::duration<double>(timeout_s), ready))
    fail(name_, "no \"" + event + "\" line within " + std::to_string(int(timeout_s)) + " s");
  if (lines_.empty()) {
    const std::string why = !start_error_.empty() ? start_error_ : run_.ok() ? "exit code 0" : run_.failure();
    fail(name_, "ended (" + why + ") without its \"" + event + "\" line");
  }
  const std::string text = lines_.front();
  lines_.pop_front();
  const json line = json::parse(text, nullptr, false);
  if (line.is_discarded() || !line.is_object()) fail(name_, "a line that is not a JSON object: " + text);
  if (line.value("event", "") != event) fail(name_, "expected the \"" + event + "\" line, got: " + text);
  return line;
}

void LineChild::send_signal(int number, const char* signal_name) {
  const std::lock_guard<std::mutex> lock(mutex_);
  if (exited_ || !pid_) fail(name_, std::string("ended before ") + signal_name + " could be sent");
  if (::kill(pid_, number) != 0) fail(name_, std::string("kill ") + signal_name + ": " + std::strerror(errno));
}

void LineChild::wait_ok(double timeout_s) {
  {
    std::unique_lock<std::mutex> lock(mutex_);
    if (!changed_.wait_for(lock, std::chrono::duration<double>(timeout_s), [&] { return exited_; }))
      fail(name_, "still running " + std::to_string(int(timeout_s)) + " s after its last line");
  }
  thread_.join();
  if (!start_error_.empty()) fail(name_, start_error_);
  if (!run_.ok()) fail(name_, "printed its last line, then " + run_.failure());
}

}  // namespace pms::bench
