// pmstream: view-dependent streaming of progressive meshes. One binary, one subcommand per job.
#include "apps/commands.h"

int main(int argc, char** argv) {
  using namespace pms::app;
  static constexpr void (*kCommands[])(CliCommand&) = {
      add_build_command,  add_info_command,    add_refine_command, add_path_command,   add_demo_command,
      add_render_command, add_compare_command, add_serve_command,  add_stream_command, add_multilevel_command};
  const CliProgram program{"pmstream", "pmstream: view-dependent progressive mesh streaming", PMSTREAM_VERSION,
                           "The experiments are a program of their own: pmstream-bench --help."};
  return run_cli(argc, argv, program, kCommands);
}
