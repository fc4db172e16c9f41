// A server child watched from outside, as an operator would: its CPU time and RSS from /proc, and the
// kernel memory of its sockets on one port from `ss -tmnH` (skmem's r, t, w and f summed over the sockets
// whose local port it is: the server's side only, not its peers').
#pragma once
#include <sys/types.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <thread>

#include "common/process_cpu.h"

namespace pms::bench {

uint64_t process_rss_bytes(pid_t pid);  // VmRSS; 0 once it is gone
uint64_t socket_memory_bytes(uint16_t port);

// The seconds from now until a whole second in which the process used under `idle` of one core, or a
// negative number when none came within `within`; `use` gets that second's share (or the lowest seen).
double seconds_to_idle(pid_t pid, double idle, std::chrono::milliseconds within, double& use);

// Samples RSS and socket memory on a thread of its own until destroyed, keeping the peaks.
class MemoryWatch {
 public:
  MemoryWatch(pid_t pid, uint16_t port);
  ~MemoryWatch();
  MemoryWatch(const MemoryWatch&) = delete;
  MemoryWatch& operator=(const MemoryWatch&) = delete;

  uint64_t peak_rss() const { return peak_rss_; }
  uint64_t peak_sockets() const { return peak_sockets_; }
  uint64_t peak_total() const { return peak_total_; }  // of one sample's sum

 private:
  std::atomic<bool> stop_{false};
  std::atomic<uint64_t> peak_rss_{0}, peak_sockets_{0}, peak_total_{0};
  std::thread thread_;
};

}  // namespace pms::bench
