// The command line's one seam: every subcommand registers its options through CliCommand, and only
// cli.cpp includes CLI11. CLI11 is header-only, so each file that included it compiled the whole parser
// again; behind this seam it is compiled once.
#pragma once
#include <cstdint>
#include <functional>
#include <initializer_list>
#include <span>
#include <string>

namespace CLI {
class App;
class Option;
}  // namespace CLI

namespace pms::app {

// One option of a command, to chain its rules on: cmd.option(...).required().show_default().
// A handle: copies name the same option, valid as long as the command line.
class CliOption {
 public:
  CliOption required();
  CliOption show_default();  // the value before parsing, in --help
  CliOption range(int64_t lo, int64_t hi);
  CliOption non_negative();
  CliOption one_of(std::initializer_list<const char*> values);
  CliOption delimiter(char separator);  // a list option split on this too
  CliOption expected(int values);       // a list option takes exactly this many
  CliOption excludes(CliOption other);
  bool given() const;  // after parsing: did the command line name it?

 private:
  friend class CliCommand;
  explicit CliOption(CLI::Option* option) : option_(option) {}
  CLI::Option* option_;
};

// What --help, --version and error lines say about the program.
struct CliProgram {
  std::string name;         // error lines read "NAME: error: ..."
  std::string description;  // --help's first line
  std::string version;      // --version
  std::string footer = {};  // --help's last lines
};

// A command or subcommand. Names as CLI11 takes them: "-o,--output" for an option, "input" for a
// positional argument.
class CliCommand {
 public:
  CliCommand subcommand(const std::string& name, const std::string& description);
  void require_subcommand();  // exactly one
  // T: std::string, bool, uint16_t, uint32_t, uint64_t, int, double, std::vector<std::string>,
  // std::vector<double> (cli.cpp instantiates these).
  template <class T>
  CliOption option(const std::string& names, T& value, const std::string& help);
  CliOption flag(const std::string& names, bool& value, const std::string& help);
  // Runs after the whole command line parsed, when this command was chosen.
  void on_run(std::function<void()> run);

 private:
  friend int run_cli(int, char**, const CliProgram&, std::span<void (*const)(CliCommand&)>);
  friend int run_cli(int, char**, const CliProgram&, void (*)(CliCommand&));
  explicit CliCommand(CLI::App* app) : app_(app) {}
  CLI::App* app_;
};

// Registers the commands, parses argv, runs the chosen command. Returns the process's exit status: CLI11's
// for usage errors and --help, 1 with "NAME: error: ..." for an exception from a command.
int run_cli(int argc, char** argv, const CliProgram& program, std::span<void (*const)(CliCommand&)> commands);
// The same for a program that is one command: `add` registers its options and its run on the program itself.
int run_cli(int argc, char** argv, const CliProgram& program, void (*add)(CliCommand&));

}  // namespace pms::app
