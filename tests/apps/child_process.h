// A program run beside the test (a `pmstream serve`), its stdout read line by line under a deadline.
#pragma once
#include <sys/types.h>

#include <chrono>
#include <string>
#include <vector>

namespace pms::test {

class ChildProcess {
 public:
  // Starts `program` with `args`; stderr goes to /dev/null.
  ChildProcess(const std::string& program, const std::vector<std::string>& args);
  ~ChildProcess();  // SIGKILL if still running, then reaped
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  // The next line of its stdout; empty when none came within `timeout` or the pipe closed.
  std::string next_line(std::chrono::milliseconds timeout);
  void signal(int number);
  // Its exit status once it ended within `timeout`; -1 otherwise (it is then killed).
  int wait(std::chrono::milliseconds timeout);

 private:
  pid_t pid_ = -1;
  int out_ = -1;
  std::string buffer_;
};

}  // namespace pms::test
