// The command line's one seam: every subcommand registers its options through CliCommand, and only
// cli.cpp includes CLI11. CLI11 is header-only, so each file that included it compiled the whole parser
// again; behind this seam it is compiled once.
#pragma once
#include <cstdint>
#include <functional>
#include <initializer_list>
#include <span>
#include <string>
#include <vector>

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
  // An output path: its extension (any case) must be one of `extensions` (".ply"), which hold `format`.
  CliOption writes(std::initializer_list<const char*> extensions, const std::string& format);
  bool given() const;        // after parsing: did the command line name it?
  std::string name() const;  // "--output" for "-o,--output"

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


// The check behind CliOption::writes, for outputs whose format an option decides: fails naming `option`
// unless `path` ends in one of `extensions` (any case).
void require_extension(const std::string& option, const std::string& path,
                       std::initializer_list<const char*> extensions, const std::string& format);

// An option only some variants of a command use (stream's modes, refine's --camera, ...).
struct VariantOption {
  CliOption option;
  std::vector<std::string> variants;  // the variants that use it
};

// Fails naming the first option of `table` that was given although `variant` does not use it, and the
// variant as the command line chose it (`chosen`, e.g. "--mode sender").
void refuse_unused_options(std::span<const VariantOption> table, const std::string& variant, const std::string& chosen);

// A command or subcommand. Names as CLI11 takes them: "-o,--output" for an option, "input" for a
// positional argument.
class CliCommand {
 public:
  CliCommand subcommand(const std::string& name, const std::string& description);
  void require_subcommand();  // exactly one
  // T: std::string, uint16_t, uint32_t, uint64_t, int, float, double, std::vector<std::string>,
  // std::vector<float> (cli.cpp instantiates these). A number must be the whole text, finite, and fit T:
  // an empty value, trailing characters, NaN or infinity are usage errors naming the option.
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
// for usage errors (one line, "NAME: error: ...") and --help, 1 with "NAME: error: ..." for an exception from
// a command. `NAME help --json` (hidden) prints every command with its options, for docs/cli.md's test.
int run_cli(int argc, char** argv, const CliProgram& program, std::span<void (*const)(CliCommand&)> commands);
// The same for a program that is one command: `add` registers its options and its run on the program itself.
int run_cli(int argc, char** argv, const CliProgram& program, void (*add)(CliCommand&));

}  // namespace pms::app
