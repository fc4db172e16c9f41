// The .pms file: writing a hierarchy with what the builder recorded, and reading one back memory-mapped.
// The layout is docs/pms-format.md.
#pragma once
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "spm/hierarchy.h"
#include "spm/split_codec.h"

namespace pms {

// What the builder recorded; stored in the file's META section as JSON.
struct BuildStats {
  std::string input_name;
  std::string tool_version;
  std::string options;          // e.g. "balanced base_vertices=0"
  uint64_t input_vertices = 0;  // of the cleaned input
  uint64_t input_faces = 0;
  uint64_t base_vertices = 0;
  uint64_t base_faces = 0;
  uint64_t vsplits = 0;
  uint32_t tree_id_bits = 0;  // ceil(log2(base_vertices))
  uint32_t node_id_bits = 0;  // max depth (the implicit leading 1 is not counted)
  uint32_t max_depth = 0;
  double seconds = 0;        // build time, load excluded
  std::string clean_report;  // human summary of what cleaning changed
};

// The .pms file: docs/pms-format.md has its properties ("Properties") and its layout.
void write_pms(const std::string& path, const Hierarchy& h, const BuildStats& stats);

class PmsFile {
 public:
  // Memory-maps and validates every section and index; throws pms::Error("PATH: section X: ...").
  static std::unique_ptr<PmsFile> open(const std::string& path);
  // Same over bytes in memory (used by tests and the fuzz target); the bytes are copied.
  static std::unique_ptr<PmsFile> from_bytes(const std::string& name, const uint8_t* data, size_t size);
  ~PmsFile();
  PmsFile(const PmsFile&) = delete;
  PmsFile& operator=(const PmsFile&) = delete;

  const ModelData& model() const { return model_; }
  const BuildStats& stats() const { return stats_; }
  uint64_t file_size() const { return size_; }
  // The header checksum, which covers every section's checksum: files with equal content have equal
  // values (HTTP ETags name a model's bytes by it).
  uint64_t content_checksum() const { return content_checksum_; }
  // The compressed split records (spm/split_codec.h; pms-format.md SRTB, SROF, SREC), checked at open:
  // internal node i's record is bits [split_offsets()[i], split_offsets()[i + 1]) of split_records().
  const SplitCodec& split_codec() const { return split_codec_; }
  std::span<const uint8_t> split_tables() const { return split_tables_; }  // split_codec() serialized
  std::span<const uint64_t> split_offsets() const { return split_offsets_; }
  std::span<const uint8_t> split_records() const { return split_records_; }

 private:
  PmsFile() = default;
  void parse(const std::string& name);
  const uint8_t* data_ = nullptr;
  uint64_t size_ = 0;
  uint64_t content_checksum_ = 0;
  bool mapped_ = false;
  std::vector<uint8_t> owned_;  // when not memory-mapped
  std::vector<uint32_t> tree_id_;
  std::vector<uint64_t> node_id_;
  ModelData model_;
  BuildStats stats_;
  SplitCodec split_codec_;
  std::span<const uint8_t> split_tables_, split_records_;
  std::span<const uint64_t> split_offsets_;
};

}  // namespace pms
