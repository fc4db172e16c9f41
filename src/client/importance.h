// What the receiver-driven client ranks its front by (cheng-ooi 2008 §4.2): the screen area of each front
// vertex's faces, so the splits that change the most pixels are asked for first. A source of its own so each
// build measures it where it draws: the native build with the software renderer's face-id buffer
// (screen_importance.h), the browser with WebGL's.
// Shared with the browser build: no asio, no threads, no renderer (docs/architecture.md, "Layers").
#pragma once
#include <cstdint>
#include <functional>
#include <vector>

#include "common/camera.h"
#include "spm/selective_mesh.h"

namespace pms::client {

struct VertexArea {
  uint32_t slot = 0;    // the vertex: a slot of the client's hierarchy
  uint64_t pixels = 0;  // pixels of its incident faces (each face's pixels count for its three corners)
};

// Whether a front vertex may be split: the caller knows which leaves the model refines further.
using CanSplit = std::function<bool(uint32_t slot)>;

class ImportanceSource {
 public:
  virtual ~ImportanceSource() = default;
  // `mesh` as `view` sees it: its active vertices that are leaves of the partial hierarchy (and pass
  // `can_split`, when given) with a non-zero area, most pixels first (ties: lower slot first, so the order is
  // deterministic). A vertex none of whose faces shows has no area and is not ranked.
  virtual const std::vector<VertexArea>& rank(const SelectiveMesh& mesh, const ViewParams& view,
                                              const CanSplit& can_split) = 0;
};

}  // namespace pms::client
