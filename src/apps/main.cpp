// pmstream: view-dependent streaming of progressive meshes. One binary, one subcommand per job.
#include <cstdio>
#include <exception>

#include "apps/commands.h"
#include "common/error.h"

int main(int argc, char** argv) {
  CLI::App app{"pmstream: view-dependent progressive mesh streaming"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string(PMSTREAM_VERSION));
  pms::app::add_build_command(app);
  pms::app::add_info_command(app);
  pms::app::add_refine_command(app);
  pms::app::add_path_command(app);
  pms::app::add_demo_command(app);
  pms::app::add_bench_command(app);
  pms::app::add_render_command(app);
  pms::app::add_compare_command(app);
  pms::app::add_serve_command(app);
  pms::app::add_stream_command(app);
  pms::app::add_multilevel_command(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pmstream: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
