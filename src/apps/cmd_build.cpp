// pmstream build IN -o OUT.pms [--greedy] [--base-vertices N] [--deviation estimate|bound] [--unnested-info] [--json]
#include <cstdio>

#include "apps/build_pipeline.h"
#include "apps/commands.h"
#include "apps/progress_bar.h"
#include "apps/resource_usage.h"
#include "spm/pms_file.h"

namespace pms::app {
namespace {

struct BuildArgs {
  std::string input, output;
  bool greedy = false, json = false, unnested_info = false;
  uint64_t base_vertices = BuildOptions{}.base_vertices;
  std::string deviation = "estimate";
};

void run_build(const BuildArgs& args) {
  Stopwatch total;
  ProgressBar bar(!args.json);
  BuildOptions options;
  options.greedy = args.greedy;
  options.base_vertices = args.base_vertices;
  options.deviation = args.deviation == "bound" ? Deviation::bound : Deviation::estimate;
  options.nested_info = !args.unnested_info;
  options.progress = bar.callback();
  const BuildRun run = build_file(args.input, args.output, options);
  bar.finish();
  const double seconds = total.seconds();
  if (args.json) {
    std::printf("%s\n", build_json(run, seconds, peak_rss_mb()).dump().c_str());
    return;
  }
  const BuildStats& s = run.stats;
  std::printf("%s -> %s\n", args.input.c_str(), args.output.c_str());
  std::printf("  cleaning:   %s\n", describe(run.clean).c_str());
  std::printf("  input:      %llu vertices, %llu faces\n", (unsigned long long)s.input_vertices,
              (unsigned long long)s.input_faces);
  std::printf("  base mesh:  %llu vertices, %llu faces\n", (unsigned long long)s.base_vertices,
              (unsigned long long)s.base_faces);
  std::printf("  vsplits:    %llu (%s)\n", (unsigned long long)s.vsplits, s.options.c_str());
  std::printf("  ids:        <%u, %u> bits (tree, node), max depth %u\n", s.tree_id_bits, s.node_id_bits, s.max_depth);
  std::printf("  time:       %.2f s (load %.2f, clean %.2f, hierarchy %.2f, write %.2f), peak RSS %.0f MB\n", seconds,
              run.load_seconds, run.clean_seconds, run.build_seconds - run.write_seconds, run.write_seconds,
              peak_rss_mb());
  std::printf("  output:     %llu bytes\n", (unsigned long long)run.output_bytes);
  if (run.texcoords_dropped) std::printf("  note:       .pms has no texture coordinates; they were left out\n");
}

}  // namespace

void add_build_command(CliCommand& app) {
  auto args = std::make_shared<BuildArgs>();
  CliCommand cmd = app.subcommand("build", "Build a view-dependent progressive mesh (.pms) from a mesh file");
  cmd.option("input", args->input, "Input mesh (PLY, OBJ, OFF, STL, glTF/GLB; may end in .gz or .xz)").required();
  cmd.option("-o,--output", args->output, "Output .pms file").required().writes({".pms"}, "a .pms model");
  cmd.flag("--greedy", args->greedy, "Classic one-at-a-time PM order (view-independent baseline)");
  cmd.option("--base-vertices", args->base_vertices,
             "Stop when the base mesh has this many vertices (0: as coarse as the mesh allows)")
      .show_default();
  cmd.option("--deviation", args->deviation,
             "Error each node claims: 'estimate' is Hoppe 1997's, measured at points of the input surface below it "
             "(the default); 'bound' covers that surface with a margin summed level by level: ~1.4x the splits for the "
             "same tolerance, which the view then keeps within it")
      .one_of({"bound", "estimate"})
      .show_default();
  cmd.flag("--unnested-info", args->unnested_info,
           "Keep each node's own refinement info instead of nesting it under its parent's (measurements: the split "
           "records then carry most values exact)");
  cmd.flag("--json", args->json, "Print one JSON object with the statistics");
  cmd.on_run([args] { run_build(*args); });
}

}  // namespace pms::app
