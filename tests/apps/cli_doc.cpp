#include "cli_doc.h"

#include <sstream>

namespace pms::test {
namespace {

// "multilevel build" from "### multilevel build"; empty for a heading that is not a command's (a command
// is lowercase words).
std::string command_of_heading(const std::string& line, size_t& level) {
  level = line.find_first_not_of('#');
  if (level == std::string::npos || level == 0 || line[level] != ' ') return "";
  const std::string name = line.substr(level + 1);
  for (const char c : name)
    if (!(std::islower(static_cast<unsigned char>(c)) || c == ' ' || c == '-')) return "";
  return name;
}

// The first word of every `code` span in a table row's first cell.
std::set<std::string> names_in_first_cell(const std::string& row) {
  std::set<std::string> names;
  const size_t end = row.find('|', 1);
  const std::string cell = row.substr(1, end == std::string::npos ? std::string::npos : end - 1);
  for (size_t open = cell.find('`'); open != std::string::npos; open = cell.find('`', open)) {
    const size_t close = cell.find('`', open + 1);
    if (close == std::string::npos) break;
    const std::string span = cell.substr(open + 1, close - open - 1);
    names.insert(span.substr(0, span.find(' ')));
    open = close + 1;
  }
  return names;
}

void visit(const nlohmann::json& value, const std::string& path, std::set<std::string>& out) {
  if (value.is_object()) {
    for (const auto& [key, child] : value.items()) visit(child, path.empty() ? key : path + "." + key, out);
    return;
  }
  bool objects = false;
  if (value.is_array())
    for (const auto& element : value)
      if (element.is_object()) {
        visit(element, path + "[]", out);
        objects = true;
      }
  if (!objects) out.insert(path);
}

}  // namespace

std::map<std::string, DocumentedCommand> parse_cli_doc(const std::string& text,
                                                       const std::set<std::string>& skip_sections) {
  std::map<std::string, DocumentedCommand> commands;
  std::istringstream in(text);
  std::string line, command;
  enum class Table { none, options, fields, other } table = Table::none;
  bool fenced = false, skipping = false;
  while (std::getline(in, line)) {
    if (line.rfind("```", 0) == 0) fenced = !fenced;
    if (fenced) continue;
    if (line.rfind("#", 0) == 0) {
      size_t level = 0;
      const std::string name = command_of_heading(line, level);
      if (level <= 2) skipping = skip_sections.count(line.substr(level + 1)) > 0;
      command = skipping ? "" : name;
      if (!command.empty()) commands[command];
      table = Table::none;
      continue;
    }
    if (line.rfind("|", 0) != 0) {
      table = Table::none;
      continue;
    }
    if (table == Table::none) {  // the header row
      const std::string first = line.substr(1, line.find('|', 1) - 1);
      const size_t word = first.find_first_not_of(' ');
      table = first.compare(word, 6, "option") == 0  ? Table::options
              : first.compare(word, 5, "field") == 0 ? Table::fields
                                                     : Table::other;
      continue;
    }
    if (command.empty() || line.rfind("| ---", 0) == 0 || table == Table::other) continue;
    auto& target = table == Table::options ? commands[command].options : commands[command].fields;
    for (const std::string& name : names_in_first_cell(line)) target.insert(name);
  }
  return commands;
}

std::set<std::string> json_fields(const nlohmann::json& value) {
  std::set<std::string> out;
  visit(value, "", out);
  return out;
}

}  // namespace pms::test
