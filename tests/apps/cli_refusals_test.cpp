// Bad command-line input is an error, never a guess (docs/cli.md, "Conventions"): a number that is not one,
// an output the command cannot write, an option the chosen variant does not use. Each is refused before any
// work, in one line naming the option. The files named need not exist: nothing is read first.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "test_support.h"

namespace pms {
namespace {

struct Refusal {
  std::string args;
  std::vector<std::string> mentions;  // each in the error line
};

void expect_refused(const std::vector<Refusal>& cases) {
  for (const Refusal& c : cases) {
    SCOPED_TRACE(c.args);
    const test::CliRun run = test::run_pmstream(c.args);
    EXPECT_NE(run.exit_code, 0);
    EXPECT_EQ(run.out, "");
    EXPECT_EQ(std::count(run.err.begin(), run.err.end(), '\n'), 1) << run.err;
    EXPECT_EQ(run.err.rfind("pmstream: error: ", 0), 0u) << run.err;
    for (const std::string& text : c.mentions) EXPECT_NE(run.err.find(text), std::string::npos) << run.err;
  }
}

TEST(CliRefusals, OutputsTheCommandCannotWrite) {
  const auto dir = test::temp_dir();
  const std::string out = (dir / "out").string();
  expect_refused({
      {"refine m.pms --full -o " + out + ".obj", {"--output", "PLY", ".ply"}},
      {"build terrain:100 -o " + out + ".ply", {"--output", ".pms"}},
      {"render m.pms --camera c.json -o " + out + ".jpg", {"--output", "PNG", ".png"}},
      {"path orbit --model m.pms --frames 2 -o " + out + ".txt", {"--output", "JSON", ".json"}},
      {"multilevel level m.pml --level 0 -o " + out + ".obj", {"--output", ".ply"}},
      {"multilevel build terrain:100 -o " + out + ".txt", {"--output", "binary", ".pml", "--ascii"}},
      {"multilevel build terrain:100 --ascii -o " + out + ".ply", {"--output", "ASCII", ".pml or .txt"}},
      {"stream --server 127.0.0.1:1 --model m --path p.json --save-mesh " + out + ".off", {"--save-mesh", ".ply"}},
  });
  std::vector<std::string> written;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) written.push_back(entry.path().string());
  EXPECT_TRUE(written.empty()) << written.front();
}

TEST(CliRefusals, NumbersThatAreNotNumbers) {
  expect_refused({
      {"multilevel level m.pml --level '' -o o.ply", {"--level", "''", "not a finite number"}},
      {"multilevel level m.pml --level 1x -o o.ply", {"--level", "'1x'"}},
      {"multilevel level m.pml --level nan -o o.ply", {"--level", "'nan'"}},
      {"multilevel level m.pml --sphere 0,0,0,inf -o o.ply", {"--sphere", "'inf'"}},
      {"refine m.pms --splits -1 -o o.ply", {"--splits", "'-1'", "whole number >= 0"}},
      {"refine m.pms --splits ' 3' -o o.ply", {"--splits", "' 3'"}},
      {"refine m.pms --camera c.json --tolerance 1e999 -o o.ply", {"--tolerance", "out of range"}},
      {"build terrain:100 -o o.pms --base-vertices 12abc", {"--base-vertices", "'12abc'"}},
      {"stream --server h:1 --model m --path p.json --laps 99999999999", {"--laps", "out of range"}},
      {"stream --server h:1 --model m --path p.json --laps 0", {"--laps"}},
      {"stream --server h:1 --model m --path p.json --tolerance=-1", {"--tolerance"}},
      {"path orbit --model m.pms --frames 0 -o p.json", {"--frames"}},
      {"path orbit --model m.pms --frames 2 --width 0x10 -o p.json", {"--width", "'0x10'"}},
      {"demo --frames ''", {"--frames", "''"}},
      {"build terrain:100:colours -o o.pms", {"terrain:100:colours", "terrain:FACES:colors"}},
      {"serve m.pms --port 70000", {"--port", "out of range"}},
  });
}

TEST(CliRefusals, StreamOptionsOutsideTheirModes) {
  const std::string stream = "stream --server 127.0.0.1:1 --model m --path p.json ";
  expect_refused({
      {stream + "--mode sender --traversal linear", {"--traversal", "--mode sender", "dag"}},
      {stream + "--budget 1000", {"--budget", "--mode sender", "dag, multilevel"}},
      {stream + "--mode vi --fetch blocks", {"--fetch", "--mode vi", "receiver"}},
      {stream + "--mode sender-plain --in-flight 2", {"--in-flight", "--mode sender-plain"}},
      {stream + "--mode dag --ids-per-request 8", {"--ids-per-request", "--mode dag"}},
      {stream + "--mode multilevel --descendant-depth 1", {"--descendant-depth", "--mode multilevel"}},
      {stream + "--mode sender --block-depth 1", {"--block-depth", "--mode sender"}},
      {stream + "--mode vi --frame-budget-ms 5", {"--frame-budget-ms", "--mode vi"}},
      {stream + "--mode multilevel --frame-answers 5", {"--frame-answers", "--mode multilevel"}},
      {stream + "--mode dag --prefetch", {"--prefetch", "--mode dag"}},
      {stream + "--mode sender --management auto", {"--management", "--mode sender", "dag"}},
      {stream + "--mode dag --management auto", {"--management", "--budget"}},
      {stream + "--mode dag --budget 5000 --management free", {"--management", "free not in {fixed,auto}"}},
      {stream + "--mode dag --frame-budget-ms 5 --fps 30", {"--frame-budget-ms", "lock-step"}},
      {stream + "--mode receiver --plain-levels", {"--plain-levels", "--mode receiver", "multilevel"}},
      {stream + "--mode receiver --reconnect 2", {"--reconnect", "--mode receiver"}},
      {stream + "--mode dag --geomorph-frames 4", {"--geomorph-frames", "--mode dag"}},
      {stream + "--mode multilevel --max-ops 10", {"--max-ops", "--mode multilevel"}},
      {stream + "--mode receiver --block-depth 3", {"--block-depth", "--fetch lists", "blocks"}},
      {stream + "--mode receiver --fetch blocks --ids-per-request 8", {"--ids-per-request", "--fetch blocks"}},
      {stream + "--mode multilevel --budget 100 --tolerance 2", {"--tolerance", "--budget"}},
      {stream + "--mode sender --ranking area", {"--ranking", "--mode sender", "receiver"}},
      {stream + "--mode receiver --stop-area 32", {"--stop-area", "--ranking area"}},
      {stream + "--mode receiver --ranking area --tolerance 2", {"--tolerance", "--stop-area"}},
      {stream + "--mode receiver --ranking area --prefetch", {"--prefetch", "--ranking area"}},
      {stream + "--mode receiver --ranking size", {"--ranking", "size not in {error,area}"}},
      {stream + "--mode bogus", {"--mode", "'bogus'"}},
  });
}

TEST(CliRefusals, OptionsOutsideTheirVariants) {
  expect_refused({
      {"refine m.pms --splits 3 --tolerance 2 -o o.ply", {"--tolerance", "--camera"}},
      {"multilevel level m.pml --camera c.json --level 1 -o o.ply", {"--level", "--camera"}},
      {"multilevel level m.pml --region 0,0,0,1,1,1 --pixels 2 -o o.ply", {"--pixels", "--region", "--camera"}},
      {"multilevel level m.pml --level 1 --pixels 2 -o o.ply", {"--pixels", "--level alone"}},
      {"multilevel build terrain:100 -o o.pml --cluster grid:8,4 --base-vertices 10", {"--base-vertices", "--cluster"}},
      {"demo --model m.pms --rebuild", {"--rebuild", ".pms"}},
      {"demo --serve --headless", {"--serve", "--headless"}},
      {"demo --serve --frames 3", {"--frames", "not used with --serve", "only with --headless"}},
      {"demo --http-port 0", {"--http-port", "without a terminal", "only with --serve"}},
      {"demo --headless --web-root w", {"--web-root", "--headless"}},
      {"serve m.pms --http-max-connections 5", {"--http-max-connections", "--http-port"}},
      {"serve m.pms --port 0 --http-request-timeout-ms 100", {"--http-request-timeout-ms", "--http-port"}},
  });
}

}  // namespace
}  // namespace pms
