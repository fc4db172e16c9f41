#include "apps/cli.h"

#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <vector>

namespace pms::app {

CliOption CliOption::required() {
  option_->required();
  return *this;
}

CliOption CliOption::show_default() {
  option_->capture_default_str();
  return *this;
}

CliOption CliOption::range(int64_t lo, int64_t hi) {
  option_->check(CLI::Range(lo, hi));
  return *this;
}

CliOption CliOption::non_negative() {
  option_->check(CLI::NonNegativeNumber);
  return *this;
}

CliOption CliOption::one_of(std::initializer_list<const char*> values) {
  option_->check(CLI::IsMember(std::vector<std::string>(values.begin(), values.end())));
  return *this;
}

CliOption CliOption::delimiter(char separator) {
  option_->delimiter(separator);
  return *this;
}

CliOption CliOption::expected(int values) {
  option_->expected(values);
  return *this;
}

CliOption CliOption::excludes(CliOption other) {
  option_->excludes(other.option_);
  return *this;
}

bool CliOption::given() const { return option_->count() > 0; }

CliCommand CliCommand::subcommand(const std::string& name, const std::string& description) {
  return CliCommand(app_->add_subcommand(name, description));
}

void CliCommand::require_subcommand() { app_->require_subcommand(1); }

template <class T>
CliOption CliCommand::option(const std::string& names, T& value, const std::string& help) {
  return CliOption(app_->add_option(names, value, help));
}

template CliOption CliCommand::option(const std::string&, std::string&, const std::string&);
template CliOption CliCommand::option(const std::string&, uint16_t&, const std::string&);
template CliOption CliCommand::option(const std::string&, uint32_t&, const std::string&);
template CliOption CliCommand::option(const std::string&, uint64_t&, const std::string&);
template CliOption CliCommand::option(const std::string&, int&, const std::string&);
template CliOption CliCommand::option(const std::string&, float&, const std::string&);
template CliOption CliCommand::option(const std::string&, double&, const std::string&);
template CliOption CliCommand::option(const std::string&, std::vector<std::string>&, const std::string&);
template CliOption CliCommand::option(const std::string&, std::vector<float>&, const std::string&);

CliOption CliCommand::flag(const std::string& names, bool& value, const std::string& help) {
  return CliOption(app_->add_flag(names, value, help));
}

void CliCommand::on_run(std::function<void()> run) { app_->callback(std::move(run)); }

namespace {

CLI::App& program_app(CLI::App& app, const CliProgram& program) {
  app.description(program.description);
  app.set_version_flag("--version", program.version);
  if (!program.footer.empty()) app.footer(program.footer);
  return app;
}

int parse_and_run(CLI::App& app, int argc, char** argv, const CliProgram& program) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: error: %s\n", program.name.c_str(), e.what());
    return 1;
  }
  return 0;
}

}  // namespace

int run_cli(int argc, char** argv, const CliProgram& program, std::span<void (*const)(CliCommand&)> commands) {
  CLI::App app;
  program_app(app, program).require_subcommand(1);
  CliCommand root(&app);
  for (auto add : commands) add(root);
  // A word where the command belongs that names none: say so, rather than CLI11's "A subcommand is required".
  if (argc > 1 && argv[1][0] != '-') {
    try {
      app.get_subcommand(argv[1]);
    } catch (const CLI::OptionNotFound&) {
      std::fprintf(stderr, "%s: error: unknown command '%s' (%s --help lists them)\n", program.name.c_str(), argv[1],
                   program.name.c_str());
      return static_cast<int>(CLI::ExitCodes::ExtrasError);
    }
  }
  return parse_and_run(app, argc, argv, program);
}

int run_cli(int argc, char** argv, const CliProgram& program, void (*add)(CliCommand&)) {
  CLI::App app;
  CliCommand root(&program_app(app, program));
  add(root);
  return parse_and_run(app, argc, argv, program);
}

}  // namespace pms::app
