// The whole model through today's single-rate web codecs, on the grid pmstream's records use: meshoptimizer's
// index and vertex codecs (after its vertex cache and fetch optimizations), those bytes again through gzip -9
// and zstd -19, and Draco at the same position bits. None has levels of detail, random access or refinement
// info; they are the bar a view-dependent stream's bits per vertex are read against (issue 19, E6's table).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "io/mesh.h"
#include "spm/position_grid.h"

namespace pms::bench {

struct SingleRateSizes {
  uint64_t vertices = 0, faces = 0;
  uint64_t meshopt_index = 0, meshopt_vertex = 0;  // bytes of each stream
  uint64_t meshopt_gzip = 0, meshopt_zstd = 0;     // both streams, compressed as one
  uint64_t draco = 0;
  std::string draco_error;  // Draco refused the mesh (its status message); draco stays 0

  uint64_t meshopt() const { return meshopt_index + meshopt_vertex; }
  double bits_per_vertex(uint64_t bytes) const { return vertices ? 8.0 * double(bytes) / double(vertices) : 0; }
};

// Positions snapped to `grid` (at most 16 bits per axis, which meshoptimizer's 16-bit lanes hold); every
// encoding is decoded again and checked against its input, so a figure is never of a broken stream
// (pms::Error naming the codec when one does not round-trip).
SingleRateSizes single_rate_codecs(const Mesh& mesh, const PositionGrid& grid);

// zlib's gzip stream at level 9 (what `gzip -9` writes, header and trailer included).
std::vector<uint8_t> gzip9(const std::vector<uint8_t>& in);

}  // namespace pms::bench
