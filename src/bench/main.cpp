// pmstream-bench [--quick] [--models bunny,horse,...] [--only build,...] [--shared DIR] [--out DIR]
//                [--soak-clients N] [--soak-minutes M] [--pmstream PATH]
// The experiments, a program of their own: it links the codecs it compares against, which pmstream does not.
#include <memory>

#include "apps/cli.h"
#include "bench/bench_run.h"

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
  cmd.option("--pmstream", args->pmstream,
             "The pmstream binary to run for builds and servers (default: the one beside pmstream-bench)");
  cmd.on_run([args, clients, minutes] {
    if (args->quick && !clients.given()) args->soak_clients = kQuickSoakClients;
    if (args->quick && !minutes.given()) args->soak_minutes = kQuickSoakMinutes;
    pms::bench::run_bench(*args);
  });
}

}  // namespace

int main(int argc, char** argv) {
  const pms::app::CliProgram program{"pmstream-bench",
                                     "pmstream-bench: the experiments of docs/architecture.md (\"Experiments\"): "
                                     "tables on stdout; a report per group, JSON and PNG in --out",
                                     PMSTREAM_VERSION};
  return pms::app::run_cli(argc, argv, program, add_bench_options);
}
