// pmstream bench [--quick] [--models bunny,horse,...] [--only build,...] [--shared DIR] [--out DIR]
//                [--soak-clients N] [--soak-minutes M]
#include <stdlib.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <ctime>
#include <fstream>

#include "apps/bench/bench.h"
#include "apps/bench/report.h"
#include "apps/commands.h"
#include "apps/resource_usage.h"
#include "common/error.h"

namespace pms::app {
namespace fs = std::filesystem;

// The experiment groups (docs/architecture.md, "Experiments"): a new group is one function and one line here.
constexpr BenchGroup kGroups[] = {
    {"build", "E12 build time and memory, E1 hierarchy statistics, terrain scaling", run_build_group},
    {"refine", "adaptation time and ops/s on a scan path, renderer speed, image quality at far/mid/close",
     run_refine_group},
    {"sender", "E2 packet bits, E3 server memory, E4 two laps, E5 bytes to satisfy tolerance, E11 many clients",
     run_sender_group},
    {"receiver",
     "whole-model bits per vertex against meshoptimizer, gzip, zstd and Draco; E7 server CPU and bytes per split; "
     "E6 PSNR against bytes received; E8 visible splits only",
     run_receiver_group},
    {"multilevel", "E10 multilevel memory against a plain mesh, LOD switch and geomorph times, bytes per level loaded",
     run_multilevel_group},
    {"soak", "many clients resuming and reconnecting for minutes: server RSS over time, failures, latency per minute",
     run_soak_group},
    {"dag", "E9 DAG traversals: time per frame, accuracy against priority, fronts, session memory, bytes down",
     run_dag_group},
};

std::span<const BenchGroup> bench_groups() { return kGroups; }

namespace {

struct BenchArgs {
  bool quick = false;
  std::vector<std::string> models, only;
  std::string shared, out = "bench-out";
  uint32_t soak_clients = 100, soak_minutes = 10;
};

// --quick's soak, unless the sizes are given.
constexpr uint32_t kQuickSoakClients = 10, kQuickSoakMinutes = 1;

std::string group_names() {
  std::string names;
  for (const BenchGroup& g : bench_groups()) names += (names.empty() ? "" : ", ") + std::string(g.name);
  return names;
}

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

std::string report_header(const BenchContext& context) {
  std::string s = "# pmstream bench\n\n";
  s += "- command: `" + context.options.command_line + "`" + (context.options.quick ? " (quick: small series)" : "") +
       "\n";
  s += "- machine: " + machine_description() + "\n";
  s += "- pmstream " + std::string(PMSTREAM_VERSION) + ", run " + utc_now() + "\n";
  s += "- models: " +
       (context.models_dir.empty() ? std::string("../shared/models not found") : context.models_dir.string()) + "\n";
  return s;
}

void run_bench(const BenchArgs& args) {
  const std::vector<const BenchGroup*> groups = select_groups(args.only);
  BenchContext context;
  context.options = {args.quick, args.models, args.out, command_line(), args.soak_clients, args.soak_minutes};
  std::error_code error;
  fs::create_directories(context.options.out_dir, error);
  if (error) fail(args.out, "cannot create the output directory: " + error.message());
  // Exec'ing /proc/self/exe runs this very binary even if the file is rebuilt during a long run.
  context.self_exe = "/proc/self/exe";
  const fs::path exe = fs::read_symlink("/proc/self/exe", error);
  const fs::path shared = locate_shared_dir(args.shared, error ? fs::path() : exe.parent_path());
  if (!shared.empty()) context.models_dir = shared / "models";
  const TempDir temp;
  context.temp_dir = temp.path();

  for (const BenchGroup* group : groups) {
    std::fprintf(stderr, "bench: group %s (%s)\n", group->name, group->experiments);
    group->run(context);
  }
  // Linux counts the pages a child inherits at fork in its ru_maxrss: this bounds that share where a
  // table could not use the child's own report.
  const std::string footer = "\n---\nThe bench process itself peaked at " + fixed(peak_rss_mb(), 0) +
                             " MB RSS. pmstream's children report their own peak (VmHWM); other tools' peak RSS "
                             "(wait4) includes at most that much inherited at fork.\n";
  write_text_file(context.options.out_dir / "report.md", report_header(context) + "\n" + context.report + footer);
  std::printf("\nbench: wrote %s\n", (context.options.out_dir / "report.md").string().c_str());
  if (!context.failures.empty()) {
    std::string list;
    for (const std::string& f : context.failures) list += (list.empty() ? "" : "; ") + f;
    fail("bench", std::to_string(context.failures.size()) + " figure(s) could not be measured: " + list);
  }
}

}  // namespace

void add_bench_command(CliCommand& app) {
  auto args = std::make_shared<BenchArgs>();
  CliCommand cmd = app.subcommand("bench",
                                  "Run the experiments (docs/architecture.md, \"Experiments\"): tables "
                                  "on stdout, report.md, JSON and PNG in --out");
  cmd.flag("--quick", args->quick, "Only the small end of every series (a smoke run)");
  cmd.option("--models", args->models,
             "Comma-separated model names in ../shared/models (default per group; "
             "build: bunny,horse,feline,skull,dragon)")
      .delimiter(',');
  cmd.option("--only", args->only, "Comma-separated experiment groups (default: all; known: " + group_names() + ")")
      .delimiter(',');
  cmd.option("--shared", args->shared,
             "Directory holding models/ (default: $PMSTREAM_SHARED_DIR, else ../shared "
             "or ../../shared from here or from the binary)");
  cmd.option("--out", args->out, "Output directory").show_default();
  CliOption clients = cmd.option("--soak-clients", args->soak_clients, "Clients of the soak group (--quick: 10)")
                          .range(1u, 10000u)
                          .show_default();
  CliOption minutes = cmd.option("--soak-minutes", args->soak_minutes, "Minutes the soak runs (--quick: 1)")
                          .range(1u, 24u * 60u)
                          .show_default();
  cmd.on_run([args, clients, minutes] {
    if (args->quick && !clients.given()) args->soak_clients = kQuickSoakClients;
    if (args->quick && !minutes.given()) args->soak_minutes = kQuickSoakMinutes;
    run_bench(*args);
  });
}

}  // namespace pms::app
