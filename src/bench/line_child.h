// A long-running child process that reports in JSON lines on stdout, one object per line with an "event"
// (`pmstream serve --json`, `pmstream-bench load-fleet`): read a line at a time, signalled, waited for. A line
// that is missing or unparsable is a pms::Error naming what was expected, never a silent default.
#pragma once
#include <sys/types.h>

#include <atomic>
#include <condition_variable>
#include <deque>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "bench/child_process.h"

namespace pms::bench {

class LineChild {
 public:
  // Starts argv; `name` starts every error ("serve", "load-fleet").
  LineChild(std::string name, const std::vector<std::string>& argv);
  ~LineChild();  // a child still running is killed (SIGKILL)
  LineChild(const LineChild&) = delete;
  LineChild& operator=(const LineChild&) = delete;

  pid_t pid() const { return pid_; }  // 0 before it started
  // The next line, which must be an object whose "event" is `event`, within `timeout_s`.
  nlohmann::json next_line(const std::string& event, double timeout_s);
  void send_signal(int number, const char* signal_name);
  // Waits for the child to exit and requires exit status 0.
  void wait_ok(double timeout_s);
  void kill();  // SIGKILL, if it still runs
  // What it wrote to stderr; read it only after wait_ok() returned.
  const std::string& log() const { return run_.err; }

 private:
  std::string name_;
  std::thread thread_;
  std::atomic<pid_t> pid_{0};
  std::mutex mutex_;
  std::condition_variable changed_;
  std::string partial_;            // stdout after the last newline
  std::deque<std::string> lines_;  // complete lines not read yet
  bool exited_ = false;
  ChildResult run_;          // written by thread_ before exited_ is set
  std::string start_error_;  // run_child could not start the program
};

}  // namespace pms::bench
