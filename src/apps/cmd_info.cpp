// pmstream info FILE.pms [--json]
#include <cstdio>

#include "apps/build_pipeline.h"
#include "apps/commands.h"
#include "spm/hierarchy.h"
#include "spm/pms_file.h"

namespace pms::app {
namespace {

void run_info(const std::string& path, bool json) {
  const auto file = PmsFile::open(path);
  const ModelData& m = file->model();
  // Structural numbers come from the arrays themselves, not from what the builder wrote.
  BuildStats s = file->stats();
  uint64_t leaves = 0;
  uint32_t depth = 0;
  for (uint32_t n = 0; n < m.node_count(); ++n) {
    leaves += m.is_leaf(n);
    depth = std::max<uint32_t>(depth, uint32_t(m.id(n).depth()));
  }
  s.base_vertices = m.root_count;
  s.base_faces = m.base_faces.size() / 3;
  s.vsplits = m.split_order.size();
  s.input_vertices = leaves;
  s.max_depth = depth;
  s.node_id_bits = depth;
  s.tree_id_bits = tree_id_bits(m.root_count);
  // The compact split records (docs/protocol.md, "Split records"): what streaming every split costs.
  const uint64_t record_bits = file->split_offsets().empty() ? 0 : file->split_offsets().back();
  const double bits_per_split = s.vsplits ? double(record_bits) / double(s.vsplits) : 0;
  if (json) {
    nlohmann::json j = stats_json(s);
    j["seconds"] = s.seconds;
    j["output_bytes"] = file->file_size();
    j["input_name"] = s.input_name;
    j["options"] = s.options;
    j["tool_version"] = s.tool_version;
    j["record_bytes"] = file->split_records().size();
    j["record_bits_per_split"] = bits_per_split;
    j["record_table_bytes"] = file->split_tables().size();
    j["record_position_bits"] = file->split_codec().position_bits();
    std::printf("%s\n", j.dump().c_str());
    return;
  }
  std::printf("%s (%llu bytes, built by pmstream %s from %s, %s)\n", path.c_str(),
              (unsigned long long)file->file_size(), s.tool_version.c_str(), s.input_name.c_str(), s.options.c_str());
  std::printf("  full mesh:  %llu vertices, %llu faces\n", (unsigned long long)s.input_vertices,
              (unsigned long long)s.input_faces);
  std::printf("  base mesh:  %llu vertices, %llu faces\n", (unsigned long long)s.base_vertices,
              (unsigned long long)s.base_faces);
  std::printf("  vsplits:    %llu\n", (unsigned long long)s.vsplits);
  std::printf("  ids:        <%u, %u> bits (tree, node), max depth %u\n", s.tree_id_bits, s.node_id_bits, s.max_depth);
  std::printf("  attributes: %s%s\n", m.normals.empty() ? "" : "normals ", m.colors.empty() ? "" : "colors");
  std::printf("  records:    %llu bytes, %.2f bits per split at %u-bit positions, code tables %llu bytes\n",
              (unsigned long long)file->split_records().size(), bits_per_split, file->split_codec().position_bits(),
              (unsigned long long)file->split_tables().size());
  std::printf("  cleaning:   %s\n", s.clean_report.c_str());
}

}  // namespace

void add_info_command(CliCommand& app) {
  auto path = std::make_shared<std::string>();
  auto json = std::make_shared<bool>(false);
  CliCommand cmd = app.subcommand("info", "Print the statistics of a .pms file");
  cmd.option("file", *path, ".pms file").required();
  cmd.flag("--json", *json, "Print one JSON object");
  cmd.on_run([path, json] { run_info(*path, *json); });
}

}  // namespace pms::app
