#include "apps/cli.h"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <exception>
#include <limits>
#include <nlohmann/json.hpp>
#include <type_traits>
#include <vector>

#include "common/error.h"

namespace pms::app {
namespace {

std::string lower(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return text;
}

template <class T>
const char* number_kind() {
  if constexpr (std::is_floating_point_v<T>) return "a finite number";
  else if constexpr (std::is_unsigned_v<T>) return "a whole number >= 0";
  else return "a whole number";
}

// CLI11 reads an empty value as 0 and lets "nan" and "inf" through: every number is checked here first,
// the whole text in T's own syntax (no sign on an unsigned, no hex, no spaces), finite and within T.
template <class T>
std::string strict_number(const std::string& text) {
  T value{};
  const char* end = text.data() + text.size();
  const auto [stop, error] = std::from_chars(text.data(), end, value);
  if (error == std::errc::result_out_of_range) {
    if constexpr (std::is_floating_point_v<T>) return "'" + text + "' is out of range";
    else
      return "'" + text + "' is out of range (" + std::to_string(std::numeric_limits<T>::lowest()) + " to " +
             std::to_string(std::numeric_limits<T>::max()) + ")";
  }
  bool ok = error == std::errc() && stop == end;
  if constexpr (std::is_floating_point_v<T>) ok = ok && std::isfinite(value);
  return ok ? std::string() : "'" + text + "' is not " + number_kind<T>();
}

template <class T>
struct NumberOf {
  using type = T;
};
template <class T>
struct NumberOf<std::vector<T>> {
  using type = T;
};

// Empty when `path` ends in one of `extensions` (any case), else what is wrong with it.
std::string extension_error(const std::string& path, const std::vector<std::string>& extensions,
                            const std::string& format) {
  for (const std::string& ext : extensions)
    if (path.size() > ext.size() && lower(path.substr(path.size() - ext.size())) == ext) return "";
  std::string list;
  for (const std::string& ext : extensions) list += (list.empty() ? "" : " or ") + ext;
  return "'" + path + "': writes " + format + " only, to a file ending in " + list;
}

nlohmann::json listing(const CLI::App& app) {
  nlohmann::json options = nlohmann::json::array(), positionals = nlohmann::json::array();
  for (const CLI::Option* option : app.get_options()) {
    if (option == app.get_help_ptr() || option == app.get_version_ptr()) continue;
    (option->get_positional() ? positionals : options).push_back(option->get_name());
  }
  nlohmann::json subcommands = nlohmann::json::object();
  for (const CLI::App* sub : app.get_subcommands([](const CLI::App* a) { return a->get_group() != ""; }))
    subcommands[sub->get_name()] = listing(*sub);
  return {{"options", options}, {"positionals", positionals}, {"subcommands", subcommands}};
}

}  // namespace

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
  option_->check(CLI::Validator(
      [](std::string& text) { return text.rfind('-', 0) == 0 ? "'" + text + "' is below 0" : std::string(); }, "",
      "non-negative"));
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

CliOption CliOption::writes(std::initializer_list<const char*> extensions, const std::string& format) {
  std::vector<std::string> allowed(extensions.begin(), extensions.end());
  option_->check(CLI::Validator([allowed, format](std::string& path) { return extension_error(path, allowed, format); },
                                "", "writes"));
  return *this;
}

bool CliOption::given() const { return option_->count() > 0; }

std::string CliOption::name() const { return option_->get_name(); }

void require_extension(const std::string& option, const std::string& path,
                       std::initializer_list<const char*> extensions, const std::string& format) {
  const std::string error = extension_error(path, {extensions.begin(), extensions.end()}, format);
  if (!error.empty()) fail(option, error);
}

void refuse_unused_options(std::span<const VariantOption> table, const std::string& variant,
                           const std::string& chosen) {
  for (const VariantOption& row : table) {
    if (!row.option.given() || std::find(row.variants.begin(), row.variants.end(), variant) != row.variants.end())
      continue;
    std::string users;
    for (const std::string& v : row.variants) users += (users.empty() ? "" : ", ") + v;
    fail(row.option.name(), "not used with " + chosen + " (only with " + users + ")");
  }
}

CliCommand CliCommand::subcommand(const std::string& name, const std::string& description) {
  return CliCommand(app_->add_subcommand(name, description));
}

void CliCommand::require_subcommand() { app_->require_subcommand(1); }

template <class T>
CliOption CliCommand::option(const std::string& names, T& value, const std::string& help) {
  CLI::Option* option = app_->add_option(names, value, help);
  using Number = typename NumberOf<T>::type;
  if constexpr (std::is_arithmetic_v<Number>)
    option->check(CLI::Validator([](std::string& text) { return strict_number<Number>(text); }, "", "number"));
  return CliOption(option);
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
  // A usage error is one line like any other error, naming the option (docs/cli.md, "Conventions").
  app.failure_message([name = program.name](const CLI::App*, const CLI::Error& e) {
    return name + ": error: " + std::string(e.what()) + "\n";
  });
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
  // Hidden (no group): the commands and options as JSON, which docs/cli.md's test compares with the page.
  bool help_json = false;
  CLI::App* help = app.add_subcommand("help", "")->group("");
  help->add_flag("--json", help_json, "Print every command and its options as one JSON object");
  help->callback([&] {
    if (help_json) std::printf("%s\n", listing(app).dump().c_str());
    else std::printf("%s", app.help().c_str());
  });
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
