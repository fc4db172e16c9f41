// docs/cli.md as data, for the test that holds it to the binary: each command's section (`## NAME`, or
// `### multilevel NAME` for a subcommand), the options its `option` tables list and the JSON fields its
// `field` tables list (docs/cli.md, "Conventions").
#pragma once
#include <map>
#include <set>
#include <string>

#include <nlohmann/json.hpp>

namespace pms::test {

struct DocumentedCommand {
  std::set<std::string> options;  // "--output"
  std::set<std::string> fields;   // "frames[].lap"
};

// Keyed by the command as typed: "build", "multilevel level". Sections headed one of `skip_sections` (and
// their subsections) are left out.
std::map<std::string, DocumentedCommand> parse_cli_doc(const std::string& text,
                                                       const std::set<std::string>& skip_sections);

// Every key of a JSON value as the doc names it: "a.b" for b in object a, "a[].b" for b in the objects of
// array a; an array of plain values is one field.
std::set<std::string> json_fields(const nlohmann::json& value);

}  // namespace pms::test
