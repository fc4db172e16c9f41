// DIR/report.md: every figure and table of the four papers, each under the experiment (E-number) that
// reproduces it, the paper's figure beside ours. It is written from the groups' GROUP.json files the
// directory holds, so a run of one group (`--only`) updates its rows and keeps the others'; an element
// whose group has not run says so. Illustrations (a diagram, an algorithm, a file layout) name the code
// that implements them and the tests that check it instead of a measurement.
#pragma once
#include <filesystem>

namespace pms::bench {

void write_paper_report(const std::filesystem::path& dir);

}  // namespace pms::bench
