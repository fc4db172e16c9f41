// The bench's Markdown reports: one per group, DIR/GROUP.md, each opening with the run's header, and
// DIR/README.md indexing every group's report the directory holds (`--out docs/results` regenerates the
// committed ones).
#pragma once
#include <filesystem>
#include <string>

#include "bench/bench.h"

namespace pms::bench {

// What every report says about the run that made it.
struct RunHeader {
  std::string command_line;  // as typed
  bool quick = false;
  std::string machine;     // machine_description()
  std::string date;        // "2026-12-06 05:30 UTC"
  std::string models_dir;  // empty: not found
};

// The header of now: this process's command line, this machine, the current date.
RunHeader current_run(const BenchContext& context);

// Writes DIR/GROUP.md: the header, the group's sections, the bench process's peak memory.
void write_group_report(const std::filesystem::path& dir, const RunHeader& run, const BenchGroup& group,
                        const std::string& sections);
// Writes DIR/README.md: every known group, linked to its report and data where DIR holds them.
void write_report_index(const std::filesystem::path& dir);

}  // namespace pms::bench
