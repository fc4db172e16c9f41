// libFuzzer target for the compressed levels' decoder (refine/multilevel_codec.h) behind addLevel: the
// input is a compressed head (64 bytes), then levels, each as a u32 little-endian length and that many
// bytes, coarsest first, as a client receives them. Every prefix either loads, with every LOD and
// geomorph of what is loaded takeable, or throws pms::Error; crashes, hangs, sanitizer reports and huge
// allocations are findings. Seed corpus: `multilevel_compressed_parts` of small builds written that way.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>

#include "common/error.h"
#include "refine/multilevel_file.h"
#include "refine/multilevel_loader.h"
#include "refine/multilevel_mesh.h"

namespace {

void touch(const pms::MultilevelMesh& m) {
  pms::MultilevelLod lod(m);
  for (uint32_t l = m.level_count(); l-- > 0;) {
    lod.set_level(l);
    for (uint32_t i : lod.indices())
      if (i >= lod.vertex_count()) __builtin_trap();
    lod.set_level(float(l) + 0.5f);
  }
}

const pms::MultilevelLimits kLimits{uint64_t(1) << 24, 1024};
constexpr size_t kHeadBytes = 64;

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < kHeadBytes) return 0;
  const std::span<const uint8_t> bytes(data, size);
  try {
    pms::MultilevelLoader loader("fuzz", bytes.first(kHeadBytes), kLimits, pms::MultilevelForm::compressed);
    size_t at = kHeadBytes;
    while (!loader.complete() && size - at >= 4) {
      uint32_t length;
      std::memcpy(&length, data + at, 4);
      at += 4;
      if (length > size - at) break;
      loader.add_level("fuzz", bytes.subspan(at, length));
      at += length;
      touch(loader.mesh());
    }
  } catch (const pms::Error&) {
  }
  return 0;
}
