#include "bench/group_reports.h"

#include <ctime>
#include <fstream>

#include "apps/resource_usage.h"
#include "bench/report.h"

namespace pms::bench {
namespace fs = std::filesystem;
namespace {

std::string shell_quote(const std::string& arg) {
  const bool plain = !arg.empty() && arg.find_first_not_of(
                                         "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                                         "0123456789-_./=,:+@%") == std::string::npos;
  if (plain) return arg;
  std::string quoted = "'";
  for (char c : arg) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

// The command line exactly as given (from /proc/self/cmdline), quoted for a shell where needed.
std::string command_line() {
  std::ifstream in("/proc/self/cmdline", std::ios::binary);
  std::string line, arg;
  while (std::getline(in, arg, '\0')) {
    if (!line.empty()) line += ' ';
    line += shell_quote(arg);
  }
  return line;
}

std::string utc_now() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%d %H:%M UTC", &tm);
  return text;
}

std::string header_lines(const RunHeader& run) {
  std::string s =
      "- command: `" + run.command_line + "`" + (run.quick ? " (quick: the small end of every series)" : "") + "\n";
  s += "- machine: " + run.machine + "\n";
  s += "- pmstream-bench " + std::string(PMSTREAM_VERSION) + ", run " + run.date + "\n";
  s += "- models: " + (run.models_dir.empty() ? std::string("../shared/models not found") : run.models_dir) + "\n";
  return s;
}

bool is_file(const fs::path& path) {
  std::error_code ignored;
  return fs::is_regular_file(path, ignored);
}

}  // namespace

RunHeader current_run(const BenchContext& context) {
  return {command_line(), context.options.quick, machine_description(), utc_now(), context.models_dir.string()};
}

void write_group_report(const fs::path& dir, const RunHeader& run, const BenchGroup& group,
                        const std::string& sections) {
  // Linux counts the pages a child inherits at fork in its ru_maxrss: this bounds that share where a
  // table could not use the child's own report.
  const std::string footer = "\n---\nThe bench process itself peaked at " + fixed(app::peak_rss_mb(), 0) +
                             " MB RSS. pmstream's children report their own peak (VmHWM); other tools' peak RSS "
                             "(wait4) includes at most that much inherited at fork.\n";
  const std::string title = "# pmstream-bench: " + std::string(group.name) + "\n\n" + group.experiments + ".\n\n";
  write_text_file(dir / (std::string(group.name) + ".md"), title + header_lines(run) + "\n" + sections + footer);
}

void write_report_index(const fs::path& dir) {
  std::string s = "# pmstream-bench reports\n\n";
  s += "One report per experiment group (docs/architecture.md, \"Experiments\"), each made by `pmstream-bench "
       "--out DIR` and opening with its run's command, machine, version and date; `--only GROUP` regenerates "
       "one. GROUP.json holds the same figures for scripts. [report.md](report.md) puts every figure and table of "
       "the four papers beside ours.\n\n";
  Table table({{"group", false}, {"what it measures", false}, {"report", false}, {"data", false}});
  for (const BenchGroup& group : bench_groups()) {
    const std::string name = group.name;
    const bool has_report = is_file(dir / (name + ".md")), has_json = is_file(dir / (name + ".json"));
    table.add_row({name, group.experiments, has_report ? "[" + name + ".md](" + name + ".md)" : "not run",
                   has_json ? "[" + name + ".json](" + name + ".json)" : ""});
  }
  write_text_file(dir / "README.md", s + table.markdown());
}

}  // namespace pms::bench
