#include "bench/bench_run.h"

#include <stdlib.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>

#include "bench/bench.h"
#include "bench/group_reports.h"
#include "bench/paper_report.h"
#include "bench/pmstream_binary.h"
#include "common/error.h"

namespace pms::bench {
namespace fs = std::filesystem;

// The experiment groups (docs/architecture.md, "Experiments"): a new group is one function and one line here.
constexpr BenchGroup kGroups[] = {
    {"build", "E12 build time and memory, E1 hierarchy statistics, terrain scaling", run_build_group},
    {"refine", "adaptation time and ops/s on a scan path, renderer speed, image quality at far/mid/close",
     run_refine_group},
    {"sender",
     "E2 packet bits and Table 2, E3 server memory, E4 two laps, E5 bytes to satisfy tolerance, E13 frame costs, "
     "E14 the same bytes, E11 many clients",
     run_sender_group},
    {"receiver",
     "whole-model bits per vertex against meshoptimizer, gzip, zstd and Draco; E7 server CPU and bytes per split; "
     "E6 PSNR against bytes received; E8 visible splits only",
     run_receiver_group},
    {"multilevel", "E10 multilevel memory against a plain mesh, LOD switch and geomorph times, bytes per level loaded",
     run_multilevel_group},
    {"soak",
     "many clients resuming and reconnecting for minutes: server RSS over time, failures, latency per minute; "
     "failover: viewers behind HAProxy resuming on another origin when theirs is killed",
     run_soak_group},
    {"fleet",
     "E11 at scale: thousands of sender-driven sessions held, a growing share flying at 30 fps, the server on one "
     "core and the load processes on the other: VIEW latency, server CPU, RSS and bytes per session, the knee",
     run_fleet_group},
    {"tier",
     "receiver-driven viewers behind an nginx cache over two origins, one killed: failures, hit rate, bytes from "
     "the cache and the origins, origin CPU per split against the sender-driven server's",
     run_tier_group},
    {"dag", "E9 DAG traversals on both of the paper's routes: time per frame, accuracy against priority, fronts, "
            "session memory, bytes down, the client's FREE/BUDGET management; Fig. 8's renders; N from the frame "
            "time left against fixed N",
     run_dag_group},
    {"attacks", "the HTTP attack classes beside a good receiver-driven client: p99, memory, CPU after, SIGTERM",
     run_attacks_group},
    {"viewer",
     "every mode's Viewer free-running at 30 fps over 0 and 50 ms round trips: frame() time, flight and settle "
     "seconds, first picture, settled mesh against lock-step",
     run_viewer_group},
    {"idle",
     "the viewer group's idle time (kim-lee-kobbelt §9): the sender-driven viewer at 30 fps over a 50 ms round trip, "
     "two laps of the orbit with AHEAD and without: frames satisfied, bytes",
     run_idle_time_group},
    {"web",
     "the browser viewer in headless Chromium: WASM refinement against native, first picture, frame rate while "
     "streaming against a replay, the page's CPU per frame by mode, memory over laps",
     run_web_group},
};

std::span<const BenchGroup> bench_groups() { return kGroups; }

std::string group_names() {
  std::string names;
  for (const BenchGroup& g : bench_groups()) names += (names.empty() ? "" : ", ") + std::string(g.name);
  return names;
}

namespace {

// Checked before anything runs, so a typo costs nothing.
std::vector<const BenchGroup*> select_groups(const std::vector<std::string>& only) {
  std::vector<const BenchGroup*> selected;
  if (only.empty()) {
    for (const BenchGroup& g : bench_groups()) selected.push_back(&g);
    return selected;
  }
  for (const std::string& name : only) {
    const auto g = std::find_if(bench_groups().begin(), bench_groups().end(),
                                [&](const BenchGroup& group) { return name == group.name; });
    if (g == bench_groups().end())
      fail("--only", "unknown experiment group '" + name + "' (known: " + group_names() + ")");
    if (std::find(selected.begin(), selected.end(), &*g) == selected.end()) selected.push_back(&*g);
  }
  return selected;
}

// Scratch space for decompressed meshes and build outputs, removed however the run ends.
class TempDir {
 public:
  TempDir() {
    std::string pattern = (fs::temp_directory_path() / "pmstream-bench-XXXXXX").string();
    if (!mkdtemp(pattern.data())) fail(pattern, "cannot create a temporary directory");
    path_ = pattern;
  }
  ~TempDir() {
    std::error_code ignored;
    fs::remove_all(path_, ignored);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

}  // namespace

void run_bench(const BenchArgs& args) {
  const std::vector<const BenchGroup*> groups = select_groups(args.only);
  BenchContext context;
  context.pmstream_exe = locate_pmstream(args.pmstream);
  context.options = {args.quick, args.models, args.out, "", args.soak_clients, args.soak_minutes};
  context.options.fleet_sessions = args.fleet_sessions;
  context.options.fleet_processes = args.fleet_processes;
  context.options.fleet_step_seconds = args.fleet_step_seconds;
  if (!args.fleet_flying.empty()) {
    context.options.fleet_flying.clear();
    for (const std::string& n : args.fleet_flying) context.options.fleet_flying.push_back(uint32_t(std::stoul(n)));
  }
  std::error_code error;
  fs::create_directories(context.options.out_dir, error);
  if (error) fail(args.out, "cannot create the output directory: " + error.message());
  const fs::path exe = fs::read_symlink("/proc/self/exe", error);
  const fs::path shared = locate_shared_dir(args.shared, error ? fs::path() : exe.parent_path());
  if (!shared.empty()) context.models_dir = shared / "models";
  const TempDir temp;
  context.temp_dir = temp.path();
  const RunHeader run = current_run(context);
  context.options.command_line = run.command_line;

  for (const BenchGroup* group : groups) {
    std::fprintf(stderr, "bench: group %s (%s)\n", group->name, group->experiments);
    context.report.clear();
    group->run(context);
    write_group_report(context.options.out_dir, run, *group, context.report);
    std::printf("\nbench: wrote %s\n", (context.options.out_dir / (std::string(group->name) + ".md")).string().c_str());
  }
  write_report_index(context.options.out_dir);
  write_paper_report(context.options.out_dir);
  if (!context.failures.empty()) {
    std::string list;
    for (const std::string& f : context.failures) list += (list.empty() ? "" : "; ") + f;
    fail("bench", std::to_string(context.failures.size()) + " figure(s) could not be measured: " + list);
  }
}

}  // namespace pms::bench
