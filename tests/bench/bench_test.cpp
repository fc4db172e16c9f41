// The bench harness's parts: the OpenMesh .pm reader (on files written here and on one written by
// OpenMesh-mkbalancedpm when it is installed), the child-process runner, the table formatter, the
// gnuplot script, and the CLI's argument errors. The bench itself is never run here.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <optional>

#include "bench/bench.h"
#include "bench/child_process.h"
#include "bench/gnuplot.h"
#include "bench/openmesh_pm.h"
#include "bench/report.h"
#include "common/error.h"
#include "protocol/packet_bits.h"
#include "test_support.h"

namespace pms::bench {
namespace {

// ---------------------------------------------------------------------------------------------
// OpenMesh .pm

struct Detail {
  uint32_t v1, vl, vr;
};

void put_u32(std::vector<uint8_t>& out, uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(uint8_t(v >> (8 * i)));
}

void put_float(std::vector<uint8_t>& out, float f) {
  uint32_t bits;
  std::memcpy(&bits, &f, 4);
  put_u32(out, bits);
}

// A .pm as mkbalancedpm lays it out (positions are arbitrary: the reader only counts and checks).
std::vector<uint8_t> make_pm(uint32_t base_vertices, const std::vector<uint32_t>& faces,
                             const std::vector<Detail>& details) {
  std::vector<uint8_t> out = {'P', 'r', 'o', 'g', 'M', 'e', 's', 'h'};
  put_u32(out, base_vertices);
  put_u32(out, uint32_t(faces.size() / 3));
  put_u32(out, uint32_t(details.size()));
  for (uint32_t v = 0; v < base_vertices; ++v)
    for (int axis = 0; axis < 3; ++axis) put_float(out, float(v + axis));
  for (uint32_t index : faces) put_u32(out, index);
  for (const Detail& d : details) {
    for (int axis = 0; axis < 3; ++axis) put_float(out, 0.5f);
    put_u32(out, d.v1);
    put_u32(out, d.vl);
    put_u32(out, d.vr);
  }
  return out;
}

constexpr uint32_t kNo = 0xffffffff;

// Base: triangle 0 1 2 and vertex 3 that no face uses. Splits: 0 -> (0, 4); 4 -> (4, 5); 1 -> (1, 6).
std::vector<uint8_t> small_pm() { return make_pm(4, {0, 1, 2}, {{0, 1, 2}, {4, 0, kNo}, {1, 5, 2}}); }

std::string error_of(const std::vector<uint8_t>& bytes) {
  try {
    parse_openmesh_pm(bytes, "t.pm");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(OpenMeshPm, CountsAndHierarchyHeight) {
  const OpenMeshPmStats s = parse_openmesh_pm(small_pm(), "t.pm");
  EXPECT_EQ(s.base_vertices, 4u);
  EXPECT_EQ(s.base_faces, 1u);
  EXPECT_EQ(s.details, 3u);
  EXPECT_EQ(s.max_depth, 2u);               // vertex 0's tree: 0 -> {0, 4}, then 4 -> {4, 5}
  EXPECT_EQ(s.isolated_base_vertices, 1u);  // vertex 3: in no face, never split
  EXPECT_EQ(s.tree_id_bits, 2u);            // ceil(log2 4)
}

TEST(OpenMeshPm, ChainOfSplitsOnOneVertexDeepensEveryTime) {
  std::vector<Detail> details;
  for (uint32_t i = 0; i < 5; ++i) details.push_back({0, 1, kNo});  // always split vertex 0 again
  const OpenMeshPmStats s = parse_openmesh_pm(make_pm(3, {0, 1, 2}, details), "chain.pm");
  EXPECT_EQ(s.max_depth, 5u);
  EXPECT_EQ(s.isolated_base_vertices, 0u);
}

TEST(OpenMeshPm, ReadsFromFile) {
  const auto path = test::temp_dir() / "small.pm";
  const auto bytes = small_pm();
  std::ofstream(path, std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
  EXPECT_EQ(read_openmesh_pm(path.string()).max_depth, 2u);
  EXPECT_THROW(read_openmesh_pm((test::temp_dir() / "missing.pm").string()), Error);
}

TEST(OpenMeshPm, RejectsTruncatedOrPaddedFiles) {
  auto bytes = small_pm();
  bytes.pop_back();
  EXPECT_NE(error_of(bytes).find("but the file has"), std::string::npos) << error_of(bytes);
  bytes.push_back(0);
  bytes.push_back(0);
  EXPECT_NE(error_of(bytes).find("but the file has"), std::string::npos);
  EXPECT_NE(error_of({'P', 'r', 'o', 'g'}).find("shorter than the 20-byte header"), std::string::npos);
  EXPECT_NE(error_of({}).find("t.pm: truncated"), std::string::npos);
}

TEST(OpenMeshPm, HugeCountsFailBeforeAllocating) {
  auto bytes = small_pm();
  for (int i = 16; i < 20; ++i) bytes[size_t(i)] = 0xff;  // n_details = 2^32 - 1
  EXPECT_NE(error_of(bytes).find("4294967295 details"), std::string::npos) << error_of(bytes);
}

TEST(OpenMeshPm, RejectsBadMagic) {
  auto bytes = small_pm();
  bytes[0] = 'X';
  EXPECT_NE(error_of(bytes).find("t.pm: not an OpenMesh progressive mesh"), std::string::npos);
}

TEST(OpenMeshPm, RejectsIndicesOutOfRange) {
  EXPECT_NE(error_of(make_pm(4, {0, 1, 9}, {})).find("base face 0 uses vertex 9 but there are 4 base vertices"),
            std::string::npos);
  // The first split may only name vertices 0..3; vertex 4 is the one it creates.
  EXPECT_NE(error_of(make_pm(4, {0, 1, 2}, {{4, 1, 2}})).find("detail 0 splits vertex 4 but only 4 vertices exist"),
            std::string::npos);
  EXPECT_NE(error_of(make_pm(4, {0, 1, 2}, {{0, 1, 2}, {1, 7, kNo}})).find("detail 1 names neighbour vertex 7"),
            std::string::npos);
  EXPECT_NE(error_of(make_pm(4, {0, 1, 2}, {{0, kNo, 4}})).find("neighbour vertex 4"), std::string::npos);
  EXPECT_EQ(error_of(make_pm(4, {0, 1, 2}, {{0, kNo, kNo}})), "");  // both absent is a valid (boundary) record
}

// A grid of n x n vertices as OFF, which OpenMesh reads.
std::string grid_off(int n) {
  std::string off = "OFF\n" + std::to_string(n * n) + " " + std::to_string(2 * (n - 1) * (n - 1)) + " 0\n";
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x)
      off += std::to_string(x) + " " + std::to_string(y) + " " + std::to_string((x * 7 + y * 3) % 5 * 0.1) + "\n";
  for (int y = 0; y + 1 < n; ++y)
    for (int x = 0; x + 1 < n; ++x) {
      const int v = y * n + x;
      off += "3 " + std::to_string(v) + " " + std::to_string(v + 1) + " " + std::to_string(v + n + 1) + "\n";
      off += "3 " + std::to_string(v) + " " + std::to_string(v + n + 1) + " " + std::to_string(v + n) + "\n";
    }
  return off;
}

// Checks the layout assumptions against the real tool: every vertex is a root or a split, and the
// height agrees with what mkbalancedpm prints itself.
TEST(OpenMeshPm, ReadsWhatMkBalancedPmWrites) {
  if (find_program("OpenMesh-mkbalancedpm").empty())
    GTEST_SKIP() << "OpenMesh-mkbalancedpm not installed (libopenmesh-apps)";
  const auto dir = test::temp_dir();
  const int n = 12;
  write_text_file(dir / "grid.off", grid_off(n));
  ChildOptions options;
  options.timeout_seconds = 120;
  const ChildResult run =
      run_child({"OpenMesh-mkbalancedpm", "-o", (dir / "grid.pm").string(), (dir / "grid.off").string()}, options);
  ASSERT_TRUE(run.ok()) << run.failure();
  const OpenMeshPmStats s = read_openmesh_pm((dir / "grid.pm").string());
  EXPECT_EQ(uint64_t(s.base_vertices) + s.details, uint64_t(n * n));
  EXPECT_GT(s.details, 0u);
  EXPECT_EQ(s.isolated_base_vertices, 0u);
  const std::string printed = "Maximum level reached: " + std::to_string(s.max_depth) + "\n";
  EXPECT_NE((run.out + run.err).find(printed), std::string::npos) << run.out << run.err;
}

// ---------------------------------------------------------------------------------------------
// Child processes

TEST(ChildProcess, CapturesOutputAndMeasures) {
  const ChildResult r = run_child({"/bin/echo", "hello", "world"});
  EXPECT_TRUE(r.ok());
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_EQ(r.out, "hello world\n");
  EXPECT_EQ(r.err, "");
  EXPECT_GT(r.peak_rss_mb, 0);
  EXPECT_GE(r.wall_seconds, 0);
  EXPECT_EQ(r.failure(), "");
}

TEST(ChildProcess, FindsProgramsOnPath) {
  EXPECT_TRUE(run_child({"sh", "-c", "exit 0"}).ok());
  EXPECT_NE(find_program("sh"), "");
  EXPECT_EQ(find_program("/bin/sh"), "/bin/sh");
  EXPECT_EQ(find_program("/etc/passwd"), "");  // not executable
  EXPECT_EQ(find_program("pmstream-no-such-program"), "");
}

TEST(ChildProcess, ReportsExitCodeAndLastStderrLine) {
  const ChildResult r = run_child({"/bin/sh", "-c", "echo out; echo first >&2; echo 'why it failed' >&2; exit 3"});
  EXPECT_FALSE(r.ok());
  EXPECT_EQ(r.exit_code, 3);
  EXPECT_EQ(r.term_signal, 0);
  EXPECT_EQ(r.out, "out\n");
  EXPECT_EQ(r.err, "first\nwhy it failed\n");
  EXPECT_EQ(r.failure(), "exit code 3: why it failed");
}

TEST(ChildProcess, ReportsTheSignal) {
  const ChildResult r = run_child({"/bin/sh", "-c", "kill -TERM $$"});
  EXPECT_FALSE(r.ok());
  EXPECT_EQ(r.term_signal, SIGTERM);
  EXPECT_NE(r.failure().find("killed by signal 15"), std::string::npos) << r.failure();
}

TEST(ChildProcess, KillsAtTheTimeout) {
  ChildOptions options;
  options.timeout_seconds = 0.2;
  const ChildResult r = run_child({"/bin/sleep", "30"}, options);
  EXPECT_TRUE(r.timed_out);
  EXPECT_FALSE(r.ok());
  EXPECT_LT(r.wall_seconds, 10);
  EXPECT_NE(r.failure().find("timed out"), std::string::npos);
}

TEST(ChildProcess, PeakRssIsTheChildsOwn) {
  // The shell keeps the 64 MB string it reads, so its peak must show it.
  const ChildResult r = run_child({"/bin/sh", "-c", "x=$(head -c 67108864 /dev/zero | tr '\\0' a); echo ${#x}"});
  ASSERT_TRUE(r.ok()) << r.failure();
  EXPECT_EQ(r.out, "67108864\n");
  EXPECT_GT(r.peak_rss_mb, 60);
}

TEST(ChildProcess, CapsCapturedOutputWithoutBlockingTheChild) {
  ChildOptions options;
  options.max_captured_bytes = 10;
  const ChildResult r = run_child({"/bin/sh", "-c", "head -c 1000000 /dev/zero"}, options);
  EXPECT_TRUE(r.ok()) << r.failure();
  EXPECT_EQ(r.out.size(), 10u);
}

TEST(ChildProcess, RedirectsStdoutToAFile) {
  const auto path = test::temp_dir() / "out.txt";
  ChildOptions options;
  options.stdout_path = path.string();
  const ChildResult r = run_child({"/bin/sh", "-c", "printf abc; printf err >&2"}, options);
  EXPECT_TRUE(r.ok());
  EXPECT_EQ(r.out, "");
  EXPECT_EQ(r.err, "err");
  std::ifstream in(path);
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(in), {}), "abc");
}

TEST(ChildProcess, StdinIsEmpty) {
  const ChildResult r = run_child({"/bin/sh", "-c", "cat; echo done"});
  EXPECT_EQ(r.out, "done\n");
}

TEST(ChildProcess, TheEnvironmentGivenJoinsAndOverridesTheInheritedOne) {
  ::setenv("PMSTREAM_TEST_INHERITED", "kept", 1);
  ::setenv("PMSTREAM_TEST_REPLACED", "old", 1);
  ChildOptions options;
  options.environment = {"PMSTREAM_TEST_REPLACED=new", "PMSTREAM_TEST_ADDED=a b"};
  const ChildResult r = run_child(
      {"/bin/sh", "-c",
       "printf '%s|%s|%s|' \"$PMSTREAM_TEST_INHERITED\" \"$PMSTREAM_TEST_REPLACED\" \"$PMSTREAM_TEST_ADDED\"; "
       "env | grep -c '^PMSTREAM_TEST_REPLACED='"},
      options);
  ::unsetenv("PMSTREAM_TEST_INHERITED");
  ::unsetenv("PMSTREAM_TEST_REPLACED");
  EXPECT_EQ(r.out, "kept|new|a b|1\n") << "the given value, once";
}

TEST(ChildProcess, ProgramsThatCannotStartThrow) {
  EXPECT_THROW(run_child({"pmstream-no-such-program"}), Error);
  EXPECT_THROW(run_child({}), Error);
  // Executable bit but no valid format: execv fails in the child and the parent must say so.
  const auto junk = test::temp_dir() / "junk";
  write_text_file(junk, std::string("\x01\x02\x03\x04", 4));
  ::chmod(junk.c_str(), 0755);
  try {
    run_child({junk.string()});
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("cannot run"), std::string::npos) << e.what();
  }
}

// ---------------------------------------------------------------------------------------------
// Tables

TEST(ReportTable, StreamsRowsAndAlignsTheWholeTable) {
  Table t({{"model", false, 0}, {"faces", true, 0}, {"µs", true, 4}});
  EXPECT_EQ(t.header(),
            "| model | faces |   µs |\n"
            "| ----- | ----: | ---: |\n");
  EXPECT_EQ(t.add_row({"bunny", "69,451", "1.5"}), "| bunny | 69,451 |  1.5 |\n");
  t.add_row({"dragonfly", "", "12.25"});
  EXPECT_EQ(t.row_count(), 2u);
  EXPECT_EQ(t.markdown(),
            "| model     |  faces |    µs |\n"
            "| --------- | -----: | ----: |\n"
            "| bunny     | 69,451 |   1.5 |\n"
            "| dragonfly |        | 12.25 |\n");
}

TEST(ReportTable, EscapesPipesAndRejectsWrongRowLength) {
  Table t({{"a|b", false, 0}});
  t.add_row({"x|y"});
  EXPECT_EQ(t.markdown(), "| a\\|b |\n| ---- |\n| x\\|y |\n");
  EXPECT_THROW(t.add_row({"1", "2"}), Error);
}

TEST(ReportTable, NumberFormats) {
  EXPECT_EQ(thousands(0), "0");
  EXPECT_EQ(thousands(999), "999");
  EXPECT_EQ(thousands(1000), "1,000");
  EXPECT_EQ(thousands(34772), "34,772");
  EXPECT_EQ(thousands(1234567), "1,234,567");
  EXPECT_EQ(thousands(18446744073709551615ull), "18,446,744,073,709,551,615");
  EXPECT_EQ(fixed(1.234, 2), "1.23");
  EXPECT_EQ(fixed(2.5, 0), "2");  // round half to even, as printf does
  EXPECT_EQ(id_bits(6, 16), "<6, 16>");
}

// ---------------------------------------------------------------------------------------------
// gnuplot

Plot two_axis_plot() {
  Plot plot{"title \"q\"", "faces", "seconds", "MB", true, true, {}};
  plot.series = {
      {"seconds", {1e5, 5e5}, {0.5, 2.5}, false}, {"empty", {}, {}, false}, {"MB", {1e5, 5e5}, {40, 180}, true}};
  return plot;
}

TEST(Gnuplot, ScriptHasTheDataAndBothAxes) {
  const std::string s = gnuplot_script(two_axis_plot(), "/tmp/x.png");
  EXPECT_NE(s.find("set output \"/tmp/x.png\""), std::string::npos);
  EXPECT_NE(s.find("set title \"title \\\"q\\\"\""), std::string::npos);
  EXPECT_NE(s.find("set logscale x\n"), std::string::npos);
  EXPECT_NE(s.find("set logscale y\n"), std::string::npos);
  EXPECT_NE(s.find("set logscale y2"), std::string::npos);
  EXPECT_NE(s.find("$s0 << EOD\n100000 0.5\n500000 2.5\nEOD\n"), std::string::npos);
  EXPECT_NE(s.find("$s2 using 1:2 with linespoints pointtype 7 title \"MB\" axes x1y2"), std::string::npos);
  EXPECT_EQ(s.find("$s1"), std::string::npos);  // an empty series is left out, not drawn as an error
}

TEST(Gnuplot, DrawsAPngOrSaysWhyNot) {
  const auto png = test::temp_dir() / "plot.png";
  Plot empty{"t", "x", "y", "", false, false, {}};
  EXPECT_EQ(plot_png(empty, png), "no data points to plot");
  const std::string skipped = plot_png(two_axis_plot(), png);
  if (find_program("gnuplot").empty()) {
    EXPECT_NE(skipped.find("gnuplot-nox"), std::string::npos);
    return;
  }
  ASSERT_EQ(skipped, "");
  std::ifstream in(png, std::ios::binary);
  char magic[8] = {};
  in.read(magic, 8);
  EXPECT_EQ(std::string(magic, 8), "\x89PNG\r\n\x1a\n");
}

// ---------------------------------------------------------------------------------------------
// Finding the shared models, and the CLI's errors

// Runs the test body from another working directory, without $PMSTREAM_SHARED_DIR.
class ScopedSearchEnvironment {
 public:
  explicit ScopedSearchEnvironment(const std::filesystem::path& cwd) : old_cwd_(std::filesystem::current_path()) {
    if (const char* env = std::getenv("PMSTREAM_SHARED_DIR")) old_env_ = env;
    ::unsetenv("PMSTREAM_SHARED_DIR");
    std::filesystem::current_path(cwd);
  }
  ~ScopedSearchEnvironment() {
    std::filesystem::current_path(old_cwd_);
    if (old_env_) ::setenv("PMSTREAM_SHARED_DIR", old_env_->c_str(), 1);
  }

 private:
  std::filesystem::path old_cwd_;
  std::optional<std::string> old_env_;
};

TEST(BenchSetup, LocatesTheSharedDirectory) {
  const auto dir = test::temp_dir();
  const auto shared = (dir / "shared").lexically_normal();
  std::filesystem::create_directories(shared / "models");
  std::filesystem::create_directories(dir / "build");
  std::filesystem::create_directories(dir / "a" / "b" / "c");
  std::filesystem::create_directories(dir / "elsewhere");
  EXPECT_EQ(locate_shared_dir(shared.string(), {}), shared);
  EXPECT_THROW(locate_shared_dir(dir.string(), {}), Error);  // given, but no models/ there

  ScopedSearchEnvironment environment(dir / "a" / "b" / "c");  // nothing at ../shared or ../../shared from here
  EXPECT_EQ(locate_shared_dir("", dir / "a" / "b" / "c"), std::filesystem::path());
  EXPECT_EQ(locate_shared_dir("", dir / "build"), shared);  // ../shared from the executable's directory
  std::filesystem::current_path(dir / "a" / "b");
  EXPECT_EQ(locate_shared_dir("", {}), shared);  // ../../shared from the working directory
  std::filesystem::current_path(dir / "a");
  EXPECT_EQ(locate_shared_dir("", {}), shared);  // ../shared from the working directory
  ::setenv("PMSTREAM_SHARED_DIR", (dir / "elsewhere").c_str(), 1);
  EXPECT_THROW(locate_shared_dir("", {}), Error);  // set, but no models/ there
}

TEST(BenchSetup, FindsModelsByShortName) {
  const auto models = test::temp_dir() / "models";
  std::filesystem::create_directories(models);
  write_text_file(models / "bunny.ply.xz", "x");
  write_text_file(models / "bunny_res2.ply.xz", "x");
  write_text_file(models / "README.md", "x");
  EXPECT_EQ(find_model(models, "bunny"), models / "bunny.ply.xz");
  EXPECT_EQ(find_model(models, "bunny_res2"), models / "bunny_res2.ply.xz");
  try {
    find_model(models, "README");
    ADD_FAILURE() << "README.md is not a model";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("no model named 'README' (available: bunny, bunny_res2)"), std::string::npos)
        << e.what();
  }
}

TEST(BenchSetup, MachineDescription) {
  const nlohmann::json m = machine_json();
  EXPECT_GE(m["nproc"].get<int>(), 1);
  EXPECT_GT(m["mem_total_gib"].get<double>(), 0);
  EXPECT_NE(machine_description().find("CPUs (nproc)"), std::string::npos);
}

// The bench's argument errors, through the real binary (cheap: they fail before any work).
TEST(BenchCommand, RejectsUnknownGroupsAndMissingSharedDir) {
  const auto out = test::temp_dir() / "out";
  const ChildResult unknown = run_child({PMSTREAM_BENCH_BINARY, "--only", "build,nope", "--out", out.string()});
  EXPECT_EQ(unknown.exit_code, 1);
  EXPECT_NE(unknown.err.find("pmstream-bench: error: --only: unknown experiment group 'nope' (known: build, refine, "
                             "sender, receiver, multilevel, soak, fleet, tier, dag, attacks, viewer, idle, web)"),
            std::string::npos)
      << unknown.err;
  EXPECT_FALSE(std::filesystem::exists(out));  // refused before creating anything
  const ChildResult shared =
      run_child({PMSTREAM_BENCH_BINARY, "--shared", (test::temp_dir() / "none").string(), "--out", out.string()});
  EXPECT_EQ(shared.exit_code, 1);
  EXPECT_NE(shared.err.find("no models/ directory"), std::string::npos) << shared.err;
}

// Builds and servers are pmstream's: a bench that cannot find it stops before it starts, saying where it looked.
TEST(BenchCommand, RefusesToRunWithoutPmstream) {
  const auto out = test::temp_dir() / "out";
  const std::string missing = (test::temp_dir() / "no-pmstream").string();
  const ChildResult run =
      run_child({PMSTREAM_BENCH_BINARY, "--pmstream", missing, "--only", "build", "--out", out.string()});
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.err.find(missing + ": no pmstream binary here (--pmstream)"), std::string::npos) << run.err;
  EXPECT_FALSE(std::filesystem::exists(out));
  // A copy of pmstream-bench alone in a directory has no pmstream beside it.
  const auto alone = test::temp_dir();
  std::filesystem::copy_file(PMSTREAM_BENCH_BINARY, alone / "pmstream-bench");
  const ChildResult lonely = run_child({(alone / "pmstream-bench").string(), "--only", "build", "--out", out.string()});
  EXPECT_EQ(lonely.exit_code, 1);
  EXPECT_NE(lonely.err.find((alone / "pmstream").string() + ": no pmstream binary here beside pmstream-bench"),
            std::string::npos)
      << lonely.err;
}

// The command no longer exists in pmstream: it says so instead of running anything.
TEST(BenchCommand, IsNotAPmstreamCommand) {
  const ChildResult run = run_child({PMSTREAM_BINARY, "bench", "--quick"});
  EXPECT_NE(run.exit_code, 0);
  EXPECT_NE(run.err.find("pmstream: error: unknown command 'bench'"), std::string::npos) << run.err;
}

}  // namespace
}  // namespace pms::bench
