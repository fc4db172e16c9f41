// A mesh as the sorted list of its faces by vertex ids: two clients' meshes compare equal exactly when they
// hold the same front with the same faces, whichever order they were refined in.
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include "spm/selective_mesh.h"

namespace pms::bench {

// A face as its three vertex ids (tree, node), rotated to start at the smallest.
using IdFace = std::array<uint64_t, 6>;

std::vector<IdFace> faces_by_id(const SelectiveMesh& mesh);

// The share of `reference`'s faces that `faces` holds too, in percent (both sorted; 100 for an empty
// reference): zheng-chan's "percentage of the correct triangles".
double shared_percent(const std::vector<IdFace>& faces, const std::vector<IdFace>& reference);

}  // namespace pms::bench
