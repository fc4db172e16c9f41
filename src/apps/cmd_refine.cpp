// pmstream refine FILE.pms (--full | --splits K) -o OUT.ply [--json]
#include <cstdio>
#include <limits>

#include "apps/commands.h"
#include "apps/refine_pipeline.h"
#include "apps/resource_usage.h"
#include "common/error.h"
#include "pm/pm.h"

namespace pms::app {
namespace {

struct RefineArgs {
  std::string input, output;
  bool full = false, json = false;
  uint64_t splits = 0;
};

void run_refine(const RefineArgs& args, bool splits_given) {
  if (args.full == splits_given) fail("", "give exactly one of --full and --splits K");
  Stopwatch clock;
  const auto file = PmsFile::open(args.input);
  const uint64_t k = args.full ? std::numeric_limits<uint64_t>::max() : args.splits;
  const Mesh mesh = refine_first_splits(file->view(), k);
  const uint64_t applied = std::min<uint64_t>(k, file->view().split_order.size());
  save_ply(mesh, args.output);
  const double seconds = clock.seconds();
  if (args.json) {
    std::printf("{\"vertices\":%zu,\"faces\":%zu,\"vsplits_applied\":%llu,\"seconds\":%.6f}\n", mesh.vertex_count(),
                mesh.face_count(), (unsigned long long)applied, seconds);
  } else {
    std::printf("%s: %llu vsplits applied -> %zu vertices, %zu faces -> %s (%.2f s)\n", args.input.c_str(),
                (unsigned long long)applied, mesh.vertex_count(), mesh.face_count(), args.output.c_str(), seconds);
  }
}

}  // namespace

void add_refine_command(CLI::App& app) {
  auto args = std::make_shared<RefineArgs>();
  CLI::App* cmd = app.add_subcommand("refine", "Refine a .pms model and write the mesh as PLY");
  cmd->add_option("file", args->input, ".pms file")->required();
  cmd->add_flag("--full", args->full, "Apply every vertex split (the finest mesh = the cleaned input)");
  CLI::Option* splits = cmd->add_option("--splits", args->splits, "Apply the first K vertex splits in stream order");
  cmd->add_option("-o,--output", args->output, "Output .ply file")->required();
  cmd->add_flag("--json", args->json, "Print one JSON object");
  cmd->callback([args, splits] { run_refine(*args, splits->count() > 0); });
}

}  // namespace pms::app
