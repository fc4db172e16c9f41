#include "bench/server_watch.h"

#include <algorithm>
#include <cstdlib>
#include <deque>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>

#include "bench/child_process.h"
#include "common/process_cpu.h"

namespace pms::bench {
namespace {

using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

// Between samples: ss runs as a child each time, and the watch must not be a load of its own.
constexpr milliseconds kSampleEvery(200);

// The sum of r, t, w and f in one "skmem:(r0,rb131072,t0,tb2626560,f0,w0,o0,bl0,d0)".
uint64_t skmem_bytes(const std::string& fields) {
  uint64_t sum = 0;
  std::istringstream in(fields);
  for (std::string field; std::getline(in, field, ',');) {
    const size_t digits = field.find_first_of("0123456789");
    if (digits == std::string::npos) continue;
    const std::string name = field.substr(0, digits);
    if (name == "r" || name == "t" || name == "w" || name == "f")
      sum += std::strtoull(field.c_str() + digits, nullptr, 10);
  }
  return sum;
}

}  // namespace

uint64_t process_rss_bytes(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/status");
  for (std::string line; std::getline(in, line);)
    if (line.rfind("VmRSS:", 0) == 0) return 1024 * std::strtoull(line.c_str() + 6, nullptr, 10);
  return 0;
}

uint64_t socket_memory_bytes(uint16_t port) {
  ChildOptions options;
  options.timeout_seconds = 10;
  std::string local_port = ":";  // (a literal + std::string here trips GCC 12's -Wrestrict)
  local_port += std::to_string(port);
  const ChildResult ss = run_child({"ss", "-tmnH", "state", "all", "sport", "=", local_port}, options);
  uint64_t sum = 0;
  for (size_t at = ss.out.find("skmem:("); at != std::string::npos; at = ss.out.find("skmem:(", at + 1)) {
    const size_t end = ss.out.find(')', at);
    sum += skmem_bytes(ss.out.substr(at + 7, end - (at + 7)));
  }
  return sum;
}

double seconds_to_idle(pid_t pid, double idle, milliseconds within, double& use) {
  const Clock::time_point start = Clock::now(), deadline = start + within;
  std::deque<std::pair<Clock::time_point, double>> samples{{start, process_cpu_seconds(pid)}};
  use = 1e9;
  while (Clock::now() < deadline) {
    std::this_thread::sleep_for(milliseconds(100));  // the sampling period of a CPU reading, not a wait
    samples.emplace_back(Clock::now(), process_cpu_seconds(pid));
    // The newest sample at least a second older than this one starts the window.
    while (samples.size() > 2 && samples.back().first - samples[1].first >= std::chrono::seconds(1))
      samples.pop_front();
    const double wall = std::chrono::duration<double>(samples.back().first - samples.front().first).count();
    if (wall < 1) continue;
    const double share = (samples.back().second - samples.front().second) / wall;
    use = std::min(use, share);
    if (share < idle) return std::chrono::duration<double>(Clock::now() - start).count();
  }
  return -1;
}

MemoryWatch::MemoryWatch(pid_t pid, uint16_t port) {
  thread_ = std::thread([this, pid, port] {
    auto raise = [](std::atomic<uint64_t>& peak, uint64_t value) { peak = std::max(peak.load(), value); };
    while (!stop_) {
      const uint64_t rss = process_rss_bytes(pid), sockets = socket_memory_bytes(port);
      raise(peak_rss_, rss);
      raise(peak_sockets_, sockets);
      raise(peak_total_, rss + sockets);
      for (const Clock::time_point next = Clock::now() + kSampleEvery; !stop_ && Clock::now() < next;)
        std::this_thread::sleep_for(milliseconds(10));
    }
  });
}

MemoryWatch::~MemoryWatch() {
  stop_ = true;
  thread_.join();
}

}  // namespace pms::bench
