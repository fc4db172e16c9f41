// Shared by the multilevel fuzz targets: what a structure that loaded must allow (every LOD and a
// geomorph of every level pair, every index inside its LOD), and the bounds the readers get.
#pragma once
#include <cstdint>

#include "multilevel/file.h"
#include "multilevel/mesh.h"

namespace fuzz {

inline void touch(const pms::MultilevelMesh& m) {
  pms::MultilevelLod lod(m);
  for (uint32_t l = m.level_count(); l-- > 0;) {
    lod.set_level(l);
    for (uint32_t i : lod.indices())
      if (i >= lod.vertex_count()) __builtin_trap();
    lod.set_level(float(l) + 0.5f);
    if (!m.texcoords.empty() && lod.texcoords().size() != 2 * size_t(lod.vertex_count())) __builtin_trap();
  }
}

inline const pms::MultilevelLimits kLimits{uint64_t(1) << 24, 1024};

}  // namespace fuzz
