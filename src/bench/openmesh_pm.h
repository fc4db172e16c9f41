// Statistics of an OpenMesh progressive mesh (.pm, as written by OpenMesh-mkbalancedpm), so the
// bench can put OpenMesh's vertex hierarchy beside ours (kim-lee-kobbelt Table 1).
//
// Layout, little-endian: the 8 ASCII bytes "ProgMesh"; uint32 n_base_vertices, n_base_faces,
// n_details; base positions (3 float32 each); base faces (3 uint32 each); then per detail i the new
// vertex's position (3 float32) and uint32 v1, vl, vr: vertex split of v1 into v1 and the new vertex
// n_base_vertices + i, with 0xffffffff for an absent vl/vr (a boundary split).
#pragma once
#include <cstdint>
#include <span>
#include <string>

#include "spm/hierarchy.h"

namespace pms::bench {

struct OpenMeshPmStats {
  uint32_t base_vertices = 0;           // OpenMesh keeps vertices no face uses: they stay roots
  uint32_t isolated_base_vertices = 0;  // roots in no base face and never split (unused input vertices)
  uint32_t base_faces = 0;
  uint32_t details = 0;       // vertex splits
  uint32_t max_depth = 0;     // height of the vertex hierarchy = node-id bits
  uint32_t tree_id_bits = 0;  // ceil(log2(base_vertices)), as for ours
};

// `name` is used in errors. Throws pms::Error for a bad magic, a size that does not match the
// header, or a vertex index out of range.
OpenMeshPmStats parse_openmesh_pm(std::span<const uint8_t> bytes, const std::string& name);
OpenMeshPmStats read_openmesh_pm(const std::string& path);

}  // namespace pms::bench
