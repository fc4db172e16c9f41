// The per-format importers behind load_mesh (io layer internal). Each one parses the whole
// (already decompressed) file and throws pms::Error "NAME: problem"; load_mesh then checks what
// every format must satisfy (indices in range, finite coordinates, at least one face).
#pragma once
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "common/progress.h"
#include "io/mesh.h"

namespace pms {

// Hand-written fast paths: progress is reported as fractions of the bytes parsed.
Mesh import_ply(const std::string& name, std::span<const uint8_t> data, const ProgressFn& progress);
Mesh import_obj(const std::string& name, std::span<const uint8_t> data, const ProgressFn& progress);
Mesh import_off(const std::string& name, std::span<const uint8_t> data, const ProgressFn& progress);

// Everything else (STL, glTF/GLB, ...): `extension` is the lower-case format hint without the dot.
Mesh import_assimp(const std::string& name, std::span<const uint8_t> data, const std::string& extension);

// Fan triangulation of a polygon fed one corner at a time: (first, previous, corner) from the
// third corner on, so faces with fewer than 3 corners add nothing.
class Fan {
 public:
  explicit Fan(std::vector<uint32_t>& indices) : indices_(indices) {}
  void add(uint32_t corner) {
    if (count_ == 0) first_ = corner;
    else if (count_ >= 2) indices_.insert(indices_.end(), {first_, prev_, corner});
    prev_ = corner;
    ++count_;
  }

 private:
  std::vector<uint32_t>& indices_;
  uint32_t first_ = 0, prev_ = 0;
  uint64_t count_ = 0;
};

// Clamped conversion of a color channel to 8 bits; `unit_range` means the value is in [0, 1].
inline uint8_t color_channel(double value, bool unit_range) {
  const double scaled = unit_range ? value * 255.0 + 0.5 : value;
  return scaled >= 255.0 ? 255 : scaled > 0.0 ? uint8_t(scaled) : 0;
}

}  // namespace pms
