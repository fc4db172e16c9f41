// pmstream-bench [--quick] [--models bunny,horse,...] [--only build,...] [--shared DIR] [--out DIR]
//                [--soak-clients N] [--soak-minutes M] [--pmstream PATH]
// The experiments, a program of their own: it links the codecs it compares against, which pmstream does not.
// pmstream-bench load-fleet --pms FILE --port P --sessions N --flying A,B,... (hidden: the fleet experiment's
//                load processes, bench/load_fleet.h)
#include <cstring>
#include <string>
#include <vector>
#include <memory>

#include "apps/cli.h"
#include "bench/bench_run.h"
#include "bench/load_fleet.h"

namespace {

using pms::app::CliCommand;
using pms::app::CliOption;
using pms::bench::BenchArgs;

// --quick's soak, unless the sizes are given.
constexpr uint32_t kQuickSoakClients = 10, kQuickSoakMinutes = 1;

void add_bench_options(CliCommand& cmd) {
  auto args = std::make_shared<BenchArgs>();
  cmd.flag("--quick", args->quick, "Only the small end of every series (a smoke run)");
  cmd.option("--models", args->models,
             "Comma-separated model names in ../shared/models (default per group; "
             "build: bunny,horse,feline,skull,dragon)")
      .delimiter(',');
  cmd.option("--only", args->only,
             "Comma-separated experiment groups (default: all; known: " + pms::bench::group_names() + ")")
      .delimiter(',');
  cmd.option("--shared", args->shared,
             "Directory holding models/ (default: $PMSTREAM_SHARED_DIR, else ../shared "
             "or ../../shared from here or from the binary)");
  cmd.option("--out", args->out, "Output directory: GROUP.md, GROUP.json and plots, README.md").show_default();
  CliOption clients = cmd.option("--soak-clients", args->soak_clients, "Clients of the soak group (--quick: 10)")
                          .range(1u, 10000u)
                          .show_default();
  CliOption minutes = cmd.option("--soak-minutes", args->soak_minutes, "Minutes the soak runs (--quick: 1)")
                          .range(1u, 24u * 60u)
                          .show_default();
  CliOption fleet_sessions = cmd.option("--fleet-sessions", args->fleet_sessions,
                                        "Sessions the fleet group opens and holds (--quick: 200)")
                                    .range(1u, 100000u)
                                    .show_default();
  CliOption fleet_flying = cmd.option("--fleet-flying", args->fleet_flying,
                                      "Sessions flying at each of the fleet group's steps (default "
                                      "0,50,100,200,400,800,1600, stopping past the knee; --quick: 0,20)")
                               .delimiter(',');
  CliOption fleet_seconds = cmd.option("--fleet-step-seconds", args->fleet_step_seconds,
                                       "Seconds each fleet step flies (--quick: 3)")
                                .show_default();
  CliOption fleet_processes = cmd.option("--fleet-processes", args->fleet_processes,
                                         "Load processes of the fleet group (--quick: 2)")
                                  .range(1u, 64u)
                                  .show_default();
  cmd.option("--pmstream", args->pmstream,
             "The pmstream binary to run for builds and servers (default: the one beside pmstream-bench)");
  cmd.on_run([args, clients, minutes, fleet_sessions, fleet_flying, fleet_seconds, fleet_processes] {
    if (args->quick && !clients.given()) args->soak_clients = kQuickSoakClients;
    if (args->quick && !minutes.given()) args->soak_minutes = kQuickSoakMinutes;
    if (args->quick && !fleet_sessions.given()) args->fleet_sessions = 200;
    if (args->quick && !fleet_flying.given()) args->fleet_flying = {"0", "20"};
    if (args->quick && !fleet_seconds.given()) args->fleet_step_seconds = 3;
    if (args->quick && !fleet_processes.given()) args->fleet_processes = 2;
    pms::bench::run_bench(*args);
  });
}

void add_load_fleet_options(CliCommand& cmd) {
  auto args = std::make_shared<pms::bench::LoadFleetArgs>();
  auto flying = std::make_shared<std::vector<std::string>>();
  cmd.option("--pms", args->pms, "The .pms file the server serves").required();
  cmd.option("--port", args->port, "The server's TCP port on 127.0.0.1").required();
  cmd.option("--sessions", args->sessions, "Sessions this process opens and holds").show_default();
  cmd.option("--first", args->first, "The first session's index in the whole fleet (its path)").show_default();
  cmd.option("--flying", *flying, "Sessions that fly at each step (SIGUSR1 starts the next)").delimiter(',');
  cmd.option("--step-seconds", args->step_seconds, "How long each step flies").show_default();
  cmd.option("--open-at-once", args->open_at_once, "Sessions opening at once").range(1u, 100000u).show_default();
  cmd.option("--tolerance", args->tolerance, "Screen-space error tau in pixels").show_default();
  cmd.option("--position-bits", args->position_bits, "The server's --position-bits (0: its default)");
  cmd.option("--answer-timeout-ms", args->answer_timeout_ms, "A session waiting longer for the server fails")
      .show_default();
  cmd.on_run([args, flying] {
    for (const std::string& n : *flying) args->flying.push_back(uint32_t(std::stoul(n)));
    pms::bench::run_load_fleet(*args);
  });
}

}  // namespace

int main(int argc, char** argv) {
  if (argc > 1 && std::strcmp(argv[1], "load-fleet") == 0) {
    const pms::app::CliProgram fleet{"pmstream-bench load-fleet",
                                     "pmstream-bench load-fleet: many sender-driven sessions from one thread, "
                                     "JSON lines on stdout (the fleet group's load processes)",
                                     PMSTREAM_VERSION};
    return pms::app::run_cli(argc - 1, argv + 1, fleet, add_load_fleet_options);
  }
  const pms::app::CliProgram program{"pmstream-bench",
                                     "pmstream-bench: the experiments of docs/architecture.md (\"Experiments\"): "
                                     "tables on stdout; a report per group, JSON and PNG in --out",
                                     PMSTREAM_VERSION};
  return pms::app::run_cli(argc, argv, program, add_bench_options);
}
