// A proxy the repo ships a configuration for (deploy/: Debian's nginx, HAProxy), run in the foreground on
// loopback by a test or the bench, on ports the kernel considered free, and stopped when destroyed.
#pragma once
#include <signal.h>
#include <sys/types.h>

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include "bench/child_process.h"

namespace pms::bench {

// A file's bytes; empty when it cannot be read (a log that was never written).
std::string file_text(const std::filesystem::path& path);

// A daemon's executable (`nginx`, `haproxy`) on PATH, else in /usr/sbin, which a user's PATH may lack;
// empty when it is not installed.
std::string find_daemon(const std::string& name);

// A port the kernel considers free now (neither nginx nor HAProxy can be asked to pick one and report it).
uint16_t free_loopback_port();

// Whether 127.0.0.1:port takes a TCP connection now.
bool accepts_connections(uint16_t port);

// How to start the daemon once: its command line and environment, and the port that accepts
// connections once it is ready.
struct DaemonStart {
  std::vector<std::string> argv;
  std::vector<std::string> environment;  // "NAME=VALUE", on top of this process's
  uint16_t ready_port = 0;
};

class LoopbackDaemon {
 public:
  // Calls `prepare` for each attempt (up to three: a port that was free may be taken by the time the
  // daemon binds it), runs what it returns and waits until its port accepts. pms::Error naming `what`,
  // with its stderr and `log_file`'s text, when no attempt came up.
  LoopbackDaemon(std::string what, std::function<DaemonStart()> prepare, std::filesystem::path log_file = {},
                 int stop_signal = SIGTERM);
  ~LoopbackDaemon();  // stop()
  LoopbackDaemon(const LoopbackDaemon&) = delete;
  LoopbackDaemon& operator=(const LoopbackDaemon&) = delete;

  // Sends the stop signal and waits for the process to exit.
  void stop();
  bool running() const { return running_ && !exited_; }
  pid_t pid() const { return pid_; }

 private:
  bool start(const DaemonStart& start);

  std::string what_;
  std::filesystem::path log_file_;
  int stop_signal_;
  ChildOptions options_;
  std::thread thread_;
  std::atomic<pid_t> pid_{0};
  std::atomic<bool> exited_{false};
  bool running_ = false;
  ChildResult run_;  // written by thread_ before exited_ is set
};

}  // namespace pms::bench
