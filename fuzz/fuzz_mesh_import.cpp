// libFuzzer target for the importers: bytes under any of these names must load or throw
// pms::Error, never crash, hang or allocate without bound. The first byte picks the name, so the
// corpus can steer the fuzzer to one format; compressed names exercise the decoders too.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "common/error.h"
#include "io/mesh.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const char* const kNames[] = {"fuzz.ply", "fuzz.obj", "fuzz.off", "fuzz.stl", "fuzz.ply.gz", "fuzz.obj.xz"};
  constexpr size_t kNameCount = sizeof kNames / sizeof kNames[0];
  if (size == 0) return 0;
  const std::vector<uint8_t> bytes(data + 1, data + size);
  try {
    const pms::Mesh mesh = pms::load_mesh_from_memory(kNames[data[0] % kNameCount], bytes);
    // What load_mesh promises: whole triangles over existing vertices, attributes for every vertex or none.
    for (uint32_t index : mesh.indices)
      if (index >= mesh.vertex_count()) __builtin_trap();
    const size_t n = mesh.vertex_count();
    if ((mesh.has_normals() && mesh.normals.size() != 3 * n) || (mesh.has_colors() && mesh.colors.size() != 4 * n) ||
        (mesh.has_texcoords() && mesh.texcoords.size() != 2 * n))
      __builtin_trap();
  } catch (const pms::Error&) {
  }
  return 0;
}
