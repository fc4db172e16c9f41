// The META section: the builder's BuildStats as a JSON object, so `pmstream info` can report
// how a file was made. Informational only: nothing structural is read from it.
#include <nlohmann/json.hpp>

#include "common/error.h"
#include "spm/pms_file.h"
#include "spm/pms_format_internal.h"

namespace pms::format {
namespace {

using nlohmann::json;

// Older or foreign writers may omit fields: a missing one keeps its default.
template <class T>
void read_field(const std::string& where, const json& j, const char* key, T& out) {
  const auto it = j.find(key);
  if (it == j.end()) return;
  try {
    it->get_to(out);
  } catch (const json::exception&) {
    section_error(where, Meta, std::string("field \"") + key + "\" has the wrong type");
  }
}

// One list of fields for both directions (const or mutable stats).
template <class Stats, class F>
void visit_fields(Stats& s, F&& f) {
  f("input_name", s.input_name);
  f("tool_version", s.tool_version);
  f("options", s.options);
  f("input_vertices", s.input_vertices);
  f("input_faces", s.input_faces);
  f("base_vertices", s.base_vertices);
  f("base_faces", s.base_faces);
  f("vsplits", s.vsplits);
  f("tree_id_bits", s.tree_id_bits);
  f("node_id_bits", s.node_id_bits);
  f("max_depth", s.max_depth);
  f("seconds", s.seconds);
  f("clean_report", s.clean_report);
}

}  // namespace

std::string stats_to_json(const BuildStats& stats) {
  json j = json::object();
  visit_fields(stats, [&](const char* key, const auto& value) { j[key] = value; });
  // File names need not be UTF-8; replace bad bytes rather than fail the whole build.
  return j.dump(-1, ' ', false, json::error_handler_t::replace);
}

BuildStats stats_from_json(const std::string& where, std::string_view text) {
  const json j = json::parse(text.begin(), text.end(), nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded()) section_error(where, Meta, "not valid JSON");
  if (!j.is_object()) section_error(where, Meta, "not a JSON object");
  BuildStats stats;
  visit_fields(stats, [&](const char* key, auto& value) { read_field(where, j, key, value); });
  return stats;
}

}  // namespace pms::format
