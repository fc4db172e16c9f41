// On-disk layout of .pms files, shared by the writer and the reader (docs/pms-format.md).
// Sections are used in place (spans into the mapping), so the layout is the host's: little-endian.
#pragma once
#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "spm/hierarchy.h"
#include "spm/pms_file.h"
#include "spm/refine_info.h"

namespace pms::format {

static_assert(std::endian::native == std::endian::little, ".pms sections are little-endian and mapped in place");

constexpr char kMagic[8] = {'P', 'M', 'S', 'T', 'R', 'E', 'A', 'M'};
// The reader refuses any other version: a section's layout or its records' coding changes with the version.
constexpr uint32_t kVersion = 7;
constexpr uint64_t kAlignment = 64;  // every section starts here, so spans into a mapping are aligned

struct FileHeader {
  char magic[8];
  uint32_t version;
  uint32_t header_bytes;  // sizeof(FileHeader); the section table follows it
  uint32_t section_count;
  uint32_t flags;  // none defined yet: must be 0
  uint64_t file_size;
  uint64_t header_checksum;  // xxh64 of header + table with this field zero
};
static_assert(sizeof(FileHeader) == 40 && offsetof(FileHeader, header_checksum) == 32);

struct SectionEntry {
  char tag[4];
  uint32_t element_size;
  uint64_t offset;
  uint64_t count;
  uint64_t checksum;  // xxh64 of the count * element_size bytes at offset
};
static_assert(sizeof(SectionEntry) == 32);

constexpr uint32_t kHasNormals = 1, kHasColors = 2;

// The HEAD section: what every other section's count is checked against.
struct HeadSection {
  uint32_t root_count;
  uint32_t node_count;
  uint32_t base_face_count;
  uint32_t flags;  // kHasNormals | kHasColors
  float bbox_min[3];
  float bbox_max[3];
  float scale;
  uint32_t reserved;  // 0
};
static_assert(sizeof(HeadSection) == 48);

// Sections in file order; Section values index kSections.
enum Section : int {
  Head,
  Meta,
  Base,
  Parent,
  Children,
  Position,
  CutLeft,
  CutRight,
  Refine,
  Leaf,
  SplitOrder,
  Normal,
  Color,
  SplitTables,
  SplitOffsets,
  SplitRecords,
  kSectionCount
};

struct SectionKind {
  char tag[5];
  uint32_t element_size;
  bool required;
};

inline constexpr SectionKind kSections[kSectionCount] = {{"HEAD", sizeof(HeadSection), true},
                                                         {"META", 1, false},
                                                         {"BASE", 12, true},
                                                         {"PRNT", 4, true},
                                                         {"CHLD", 4, true},
                                                         {"POSI", 12, true},
                                                         {"CUTL", 4, true},
                                                         {"CUTR", 4, true},
                                                         {"RINF", sizeof(RefineInfo), true},
                                                         {"LEAF", 4, true},
                                                         {"SORD", 4, true},
                                                         {"NRML", 12, false},
                                                         {"COLR", 4, false},
                                                         {"SRTB", 1, true},
                                                         {"SROF", 8, true},
                                                         {"SREC", 1, true}};

// xxh64 of the header and section table with the header_checksum field counted as zero.
uint64_t header_checksum(const uint8_t* header_and_table, uint64_t bytes);

struct LocatedSection {
  const uint8_t* data = nullptr;
  uint64_t count = 0;  // elements of kSections[..].element_size bytes
  bool present = false;
};
using SectionMap = std::array<LocatedSection, kSectionCount>;

// Checks the header (magic, version, sizes, checksum), then every table entry (alignment, bounds
// with overflow-safe arithmetic, no overlap, element size, checksum) and that the required
// sections exist; returns where the known sections are. Unknown tags are checked and skipped.
SectionMap locate_sections(const std::string& where, const uint8_t* data, uint64_t size);

// Numbers in error messages.
inline std::string str(uint64_t value) { return std::to_string(value); }

// "PATH: section TAG: what" — every reader and validator error goes through here.
[[noreturn]] void section_error(const std::string& where, Section section, const std::string& what);

// Everything validate_model() checks beyond array lengths: the forest structure, breadth-first
// order, depth <= 63, leaves, cut vertices, base faces, split order, finite values, refinement
// info. Node arrays must already have node_count() elements (normals/colors: that or empty) and
// base_faces a multiple of 3; tree_id/node_id are resized and filled. O(n) time, n bytes of scratch.
void validate_model(const std::string& where, const ModelData& model, std::vector<uint32_t>& tree_id,
                    std::vector<uint64_t>& node_id);

// META: BuildStats as JSON. Missing fields keep their defaults; malformed JSON or a field of the
// wrong type is a pms::Error naming section META.
std::string stats_to_json(const BuildStats& stats);
BuildStats stats_from_json(const std::string& where, std::string_view json);

}  // namespace pms::format
