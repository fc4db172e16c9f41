// Multilevel mesh files: the paper's ASCII format (gueziec et al. 1999, Fig. 6 and Fig. 13) and the binary
// form with one checksummed section per level (docs/multilevel-format.md).
#pragma once
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "multilevel/mesh.h"

namespace pms {

// Bounds on what a reader accepts from a file (everything in it is hostile).
struct MultilevelLimits {
  uint64_t max_file_bytes = uint64_t(4) << 30;
  uint32_t max_levels = 1u << 16;
};

// ASCII: per level from the coarsest, `{` vertex coordinates `}` then `{` triangles, each followed by the
// representatives it states `}`; `#` starts a comment to the end of the line; numbers are separated by
// commas and/or white space. Errors name the line: "WHERE: line N: what". Positions only: the paper's
// format has no normals, colours or texture coordinates (its Fig. 9 model has them, but Fig. 6's file
// "doesn't show this"), and no place for the representatives only geomorphs use
// (geomorph_representatives_per_level): they are left out, so what reads back has the discrete LODs'.
MultilevelMesh parse_multilevel_ascii(const std::string& where, std::string_view text,
                                      const MultilevelLimits& limits = {});
std::string format_multilevel_ascii(const MultilevelMesh& mesh);

// Binary (docs/multilevel-format.md): errors name the section or byte offset.
MultilevelMesh parse_multilevel_binary(const std::string& where, std::span<const uint8_t> bytes,
                                       const MultilevelLimits& limits = {});
std::vector<uint8_t> format_multilevel_binary(const MultilevelMesh& mesh);

// Recomputes every section checksum and the header checksum of a binary file changed on purpose, where its
// table allows: tests and the fuzzer use it so that their changes reach the checks behind the checksums.
void reseal_multilevel_binary(std::span<uint8_t> bytes);

// Either form, told apart by the binary magic. Writing goes through PATH.tmp and a rename.
MultilevelMesh read_multilevel(const std::string& path, const MultilevelLimits& limits = {});
void write_multilevel(const std::string& path, const MultilevelMesh& mesh, bool ascii);
bool is_multilevel_binary(std::span<const uint8_t> bytes);

}  // namespace pms
