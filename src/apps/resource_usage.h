// Peak resident memory and wall time, as reported by build and bench.
#pragma once
#include <sys/resource.h>

#include <chrono>
#include <cstdio>

namespace pms::app {

// This program's own peak: VmHWM, of the address space exec gave it. ru_maxrss would also count the
// pages a process had before exec, i.e. its parent's (a bench child forked from a bench holding models).
inline double peak_rss_mb() {
  if (std::FILE* status = std::fopen("/proc/self/status", "r")) {
    char line[256];
    unsigned long long kb = 0;
    bool found = false;
    while (!found && std::fgets(line, sizeof line, status)) found = std::sscanf(line, "VmHWM: %llu kB", &kb) == 1;
    std::fclose(status);
    if (found) return double(kb) / 1024.0;
  }
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return double(usage.ru_maxrss) / 1024.0;  // Linux reports kilobytes
}

class Stopwatch {
 public:
  double seconds() const { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count(); }

 private:
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

}  // namespace pms::app
