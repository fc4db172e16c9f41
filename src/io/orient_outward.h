// The last cleaning step: closed surfaces face outward. Hoppe's back-face test, which every mode's
// refinement runs, takes a face's winding as its outside; a closed scan wound inside out (the shared horse
// is) has its visible side culled as "back-facing" and never refined, however small τ is.
#pragma once
#include <cstddef>

#include "io/mesh.h"

namespace pms {

struct OutwardReport {
  size_t components = 0;  // closed components turned outward
  size_t faces = 0;       // their faces
};

// For an oriented 2-manifold: every closed face component (each edge shared by two of its faces) faces
// out (positive signed volume) unless an odd number of other closed components enclose it, in which case
// it is the wall of a cavity and faces in. One that does not has every face's winding reversed and its
// vertices' normals negated. Open components keep their winding: without an inside there is nothing to
// decide it by. When no closed component has a negative volume (the usual case) nothing else is tested, so
// a cavity's wall wound outward inside a correctly wound shell is left as it is.
OutwardReport orient_closed_components_outward(Mesh& mesh);

}  // namespace pms
