// Where the bench finds its inputs and what it says about the machine it ran on.
#include <sched.h>
#include <sys/utsname.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>

#include "bench/bench.h"
#include "bench/report.h"
#include "common/error.h"

namespace pms::bench {
namespace fs = std::filesystem;
namespace {

bool has_models(const fs::path& dir) {
  std::error_code ignored;
  return fs::is_directory(dir / "models", ignored);
}

// The value after "KEY:" on the first line of a /proc file that starts with KEY; empty if none.
std::string proc_field(const char* file, const std::string& key) {
  std::ifstream in(file);
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind(key, 0) != 0) continue;
    const size_t colon = line.find(':');
    if (colon == std::string::npos) continue;
    const size_t begin = line.find_first_not_of(" \t", colon + 1);
    return begin == std::string::npos ? "" : line.substr(begin);
  }
  return "";
}

}  // namespace

fs::path locate_shared_dir(const std::string& explicit_dir, const fs::path& exe_dir) {
  if (!explicit_dir.empty()) {
    if (!has_models(explicit_dir)) fail(explicit_dir, "--shared: there is no models/ directory here");
    return fs::absolute(explicit_dir).lexically_normal();
  }
  if (const char* env = std::getenv("PMSTREAM_SHARED_DIR"); env && *env) {
    if (!has_models(env)) fail(env, "PMSTREAM_SHARED_DIR: there is no models/ directory here");
    return fs::absolute(env).lexically_normal();
  }
  std::error_code ignored;
  for (const fs::path& base : {fs::current_path(ignored), exe_dir}) {
    if (base.empty()) continue;
    for (const char* up : {"../shared", "../../shared"}) {
      const fs::path candidate = (base / up).lexically_normal();
      if (has_models(candidate)) return candidate;
    }
  }
  return {};
}

fs::path find_model(const fs::path& models_dir, const std::string& name) {
  std::vector<fs::path> matches;
  std::vector<std::string> names;
  std::error_code error;
  for (const auto& entry : fs::directory_iterator(models_dir, error)) {
    const std::string file = entry.path().filename().string();
    const size_t dot = file.find('.');
    if (!entry.is_regular_file() || dot == 0 || dot == std::string::npos || entry.path().extension() == ".md") continue;
    const std::string stem = file.substr(0, dot);
    if (stem == name) matches.push_back(entry.path());
    names.push_back(stem);
  }
  if (error) fail(models_dir.string(), "cannot list: " + error.message());
  if (!matches.empty()) return *std::min_element(matches.begin(), matches.end());
  std::sort(names.begin(), names.end());
  names.erase(std::unique(names.begin(), names.end()), names.end());
  std::string list;
  for (const std::string& n : names) list += (list.empty() ? "" : ", ") + n;
  fail(models_dir.string(), "no model named '" + name + "' (available: " + list + ")");
}

nlohmann::json machine_json() {
  cpu_set_t cpus;
  CPU_ZERO(&cpus);
  const int nproc = sched_getaffinity(0, sizeof cpus, &cpus) == 0 ? CPU_COUNT(&cpus) : 0;  // what `nproc` prints
  const std::string mem = proc_field("/proc/meminfo", "MemTotal");                         // "16330040 kB"
  utsname system{};
  uname(&system);
  return {{"nproc", nproc},
          {"cpu_model", proc_field("/proc/cpuinfo", "model name")},
          {"mem_total_gib", mem.empty() ? 0.0 : std::strtod(mem.c_str(), nullptr) / (1024.0 * 1024.0)},
          {"kernel", std::string(system.sysname) + " " + system.release}};
}

std::string machine_description() {
  const nlohmann::json m = machine_json();
  const std::string cpu = m["cpu_model"].get<std::string>();
  return std::to_string(m["nproc"].get<int>()) + " CPUs (nproc), " + (cpu.empty() ? "unknown CPU model" : cpu) + ", " +
         fixed(m["mem_total_gib"].get<double>(), 1) + " GiB RAM, " + m["kernel"].get<std::string>();
}

void write_text_file(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
  out.close();
  if (!out) fail(path.string(), "cannot write");
}

bool skipped_without_models(BenchContext& context, const std::string& section) {
  if (!context.models_dir.empty()) return false;
  context.report += section + "Skipped: ../shared/models not found.\n\n";
  return true;
}

}  // namespace pms::bench
