// The invariant the builder relies on: an oriented 2-manifold, boundaries allowed.
#pragma once
#include <string>

#include "io/mesh.h"

namespace pms {

// Every index in range, no degenerate faces (repeated corner or exactly zero area) and no duplicate
// faces, every directed edge used once (so an edge has at most two faces, oppositely oriented), every
// vertex's faces one fan (an edge-connected chain or cycle), no unused vertex. Linear time.
// On failure `why` (if given) names the first problem found.
bool is_oriented_manifold(const Mesh& mesh, std::string* why = nullptr);

// The cross product of face f's edges is exactly zero (cleaning drops such faces, the check refuses
// them). float differences and their products are exact in double for coordinates within 2^29 of each
// other, so this is the exact test, not a tolerance.
bool has_zero_area(const Mesh& mesh, size_t f);

}  // namespace pms
