// The bench's reports: one Markdown file per group with the run's header, and the index of what a
// directory holds (`--out docs/results` regenerates the committed ones through these).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>

#include "bench/bench.h"
#include "bench/group_reports.h"
#include "test_support.h"

namespace pms::bench {
namespace {

std::string slurp(const std::filesystem::path& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

const BenchGroup& group_named(const std::string& name) {
  for (const BenchGroup& g : bench_groups())
    if (g.name == name) return g;
  throw std::runtime_error("no group " + name);
}

TEST(GroupReports, EachGroupsReportOpensWithTheRunsHeader) {
  const auto dir = test::temp_dir();
  const RunHeader run{"pmstream-bench --quick --only dag", true, "2 CPUs (nproc), a test machine",
                      "2026-12-06 05:30 UTC", "/models"};
  write_group_report(dir, run, group_named("dag"), "## E9\n\n| a |\n| - |\n");
  const std::string text = slurp(dir / "dag.md");
  EXPECT_EQ(text.rfind("# pmstream-bench: dag\n\nE9 DAG traversals", 0), 0u) << text;
  EXPECT_NE(text.find("- command: `pmstream-bench --quick --only dag` (quick: the small end of every series)\n"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("- machine: 2 CPUs (nproc), a test machine\n"), std::string::npos);
  EXPECT_NE(text.find("- pmstream-bench " + std::string(PMSTREAM_VERSION) + ", run 2026-12-06 05:30 UTC\n"),
            std::string::npos);
  EXPECT_NE(text.find("- models: /models\n\n## E9\n"), std::string::npos) << text;
  EXPECT_NE(text.find("The bench process itself peaked at"), std::string::npos);
}

TEST(GroupReports, IndexLinksTheReportsTheDirectoryHolds) {
  const auto dir = test::temp_dir();
  const RunHeader run{"pmstream-bench", false, "m", "d", ""};
  write_group_report(dir, run, group_named("build"), "");
  std::ofstream(dir / "build.json") << "{}\n";
  write_report_index(dir);
  const std::string index = slurp(dir / "README.md");
  EXPECT_NE(index.find("[build.md](build.md)"), std::string::npos) << index;
  EXPECT_NE(index.find("[build.json](build.json)"), std::string::npos) << index;
  for (const BenchGroup& g : bench_groups()) EXPECT_NE(index.find("| " + std::string(g.name) + " "), std::string::npos);
  EXPECT_EQ(index.find("[dag.md]"), std::string::npos);  // not run here: listed, not linked
  EXPECT_NE(index.find("not run"), std::string::npos);
}

}  // namespace
}  // namespace pms::bench
