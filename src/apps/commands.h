// Each subcommand of the `pmstream` binary registers itself on the CLI11 app.
#pragma once
#include <CLI/CLI.hpp>

namespace pms::app {

void add_build_command(CLI::App& app);
void add_info_command(CLI::App& app);
void add_refine_command(CLI::App& app);
void add_path_command(CLI::App& app);
void add_demo_command(CLI::App& app);
void add_bench_command(CLI::App& app);
void add_render_command(CLI::App& app);
void add_compare_command(CLI::App& app);
void add_serve_command(CLI::App& app);
void add_stream_command(CLI::App& app);
void add_multilevel_command(CLI::App& app);

}  // namespace pms::app
