// pmstream-bench: the experiments of docs/architecture.md ("Experiments"), in groups. Each group prints its tables
// to stdout as they fill (progress lines go to stderr), writes its report's sections into the context and its
// own GROUP.json and plots into the output directory; the run makes the report GROUP.md of them.
#pragma once
#include <filesystem>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <vector>

namespace pms::bench {

struct BenchOptions {
  bool quick = false;               // the small end of every series, for a smoke run
  std::vector<std::string> models;  // short names ("bunny"); empty: each group's default list
  std::filesystem::path out_dir;
  std::string command_line;     // as typed, for the report
  uint32_t soak_clients = 100;  // the soak group's load (--soak-clients, --soak-minutes)
  uint32_t soak_minutes = 10;
  // The fleet group's load (--fleet-sessions, --fleet-flying, --fleet-step-seconds, --fleet-processes).
  uint32_t fleet_sessions = 5000;
  std::vector<uint32_t> fleet_flying = {0, 50, 100, 200, 400, 800, 1600};
  double fleet_step_seconds = 10;
  uint32_t fleet_processes = 4;
};

struct BenchContext {
  BenchOptions options;
  std::filesystem::path models_dir;  // ../shared/models; empty when not found (real-model parts skipped)
  std::filesystem::path temp_dir;    // scratch for this run, removed afterwards
  std::string pmstream_exe;          // the pmstream binary, run as a child for our builds and servers
  std::string report;                // the running group's report so far; it appends its sections
  // One line per figure that could not be measured (a server that did not report): the report says so
  // where the figure would be, and the bench exits non-zero once the reports are written.
  std::vector<std::string> failures;
};

using BenchGroupFn = void (*)(BenchContext&);

struct BenchGroup {
  const char* name;         // as given to --only
  const char* experiments;  // what it reproduces, for --help and the report
  BenchGroupFn run;
};

// Every experiment group, in the order a full run executes them.
std::span<const BenchGroup> bench_groups();

// E1, E12 and the terrain scaling series (bench_build.cpp).
void run_build_group(BenchContext& context);
// Adaptation, renderer and image quality of the refinement engine (bench_refine.cpp).
void run_refine_group(BenchContext& context);
// E2, E3, E4, E5, E13, E14 and E11 of the sender-driven mode (bench_sender.cpp).
void run_sender_group(BenchContext& context);
// Receiver-driven against sender-driven and single-rate codecs: whole-model bits, E7, E6, E8 (bench_receiver.cpp).
void run_receiver_group(BenchContext& context);
// E10: multilevel memory, LOD switch and geomorph times, bytes per level loaded (bench_multilevel.cpp).
void run_multilevel_group(BenchContext& context);
// Requirement 8's soak: many resuming clients against one server for minutes (bench_soak.cpp), then the
// failover figure.
void run_soak_group(BenchContext& context);
// E11's fleet: thousands of sessions held, a growing share flying, server and load on a core each
// (bench_fleet.cpp).
void run_fleet_group(BenchContext& context);
// Sender-driven viewers behind HAProxy resuming on another origin when theirs is killed (bench_failover.cpp).
void run_failover_figure(BenchContext& context);
// Receiver-driven viewers behind the nginx cache tier over two origins, one killed (bench_tier.cpp).
void run_tier_group(BenchContext& context);
// E9: the DAG mode's three traversals along a scan route (bench_dag.cpp).
void run_dag_group(BenchContext& context);
// The HTTP attack classes in their three groups beside a good receiver-driven client (bench_attacks.cpp).
void run_attacks_group(BenchContext& context);
// Every mode's Viewer free-running over a delaying link (bench_viewer.cpp).
void run_viewer_group(BenchContext& context);
// The viewer group's idle-time experiment: the sender-driven viewer with and without AHEAD (bench_idle_time.cpp).
void run_idle_time_group(BenchContext& context);
// The browser viewer in headless Chromium against the native client (bench_web.cpp).
void run_web_group(BenchContext& context);

// The directory holding models/: `explicit_dir` (--shared) if given, else $PMSTREAM_SHARED_DIR, else
// ../shared or ../../shared relative to the working directory and then to `exe_dir`. An explicit
// directory without models/ is an error; otherwise returns empty when nothing is found.
std::filesystem::path locate_shared_dir(const std::string& explicit_dir, const std::filesystem::path& exe_dir);

// The file in `models_dir` for a short model name ("bunny" -> bunny.ply.xz); pms::Error listing the
// available names when there is none.
std::filesystem::path find_model(const std::filesystem::path& models_dir, const std::string& name);

// A group that needs ../shared/models and finds none says so under its `section` heading in the report:
// true when it must skip.
bool skipped_without_models(BenchContext& context, const std::string& section);

// "2 CPUs (nproc), <model name from /proc/cpuinfo>, 15.6 GiB RAM" for the report header.
std::string machine_description();
nlohmann::json machine_json();

// Writes `text` to `path`, pms::Error naming the file when it cannot.
void write_text_file(const std::filesystem::path& path, const std::string& text);

}  // namespace pms::bench
