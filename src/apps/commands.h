// Each subcommand of the `pmstream` binary registers itself on the command line (apps/cli.h).
#pragma once
#include "apps/cli.h"

namespace pms::app {

void add_build_command(CliCommand& app);
void add_info_command(CliCommand& app);
void add_refine_command(CliCommand& app);
void add_path_command(CliCommand& app);
void add_demo_command(CliCommand& app);
void add_render_command(CliCommand& app);
void add_compare_command(CliCommand& app);
void add_serve_command(CliCommand& app);
void add_stream_command(CliCommand& app);
void add_multilevel_command(CliCommand& app);

}  // namespace pms::app
