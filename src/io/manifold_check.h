// The invariant the builder relies on: an oriented 2-manifold, boundaries allowed.
#pragma once
#include <string>

#include "io/mesh.h"

namespace pms {

// Every index in range, no degenerate or duplicate faces, every directed edge used once (so an
// edge has at most two faces, oppositely oriented), every vertex's faces one fan, no unused vertex.
// On failure `why` (if given) names the first problem found.
bool is_oriented_manifold(const Mesh& mesh, std::string* why = nullptr);

}  // namespace pms
