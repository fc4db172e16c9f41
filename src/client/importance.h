// What the receiver-driven client ranks its front by (cheng-ooi 2008 §4.2): the screen area of each front
// vertex's faces, so the splits that change the most pixels are asked for first. A source of its own so each
// build measures it where it draws: the native build with the software renderer's face-id buffer
// (screen_importance.h), the browser with WebGL's.
// Shared with the browser build: no asio, no threads, no renderer (docs/architecture.md, "Layers").
#pragma once
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "common/camera.h"
#include "spm/selective_mesh.h"
#include "spm/vertex_id.h"

namespace pms::client {

struct VertexArea {
  uint32_t slot = 0;    // the vertex: a slot of the client's hierarchy
  uint64_t pixels = 0;  // pixels of its incident faces (each face's pixels count for its three corners)
};

// Whether a front vertex may be split: the caller knows which leaves the model refines further.
using CanSplit = std::function<bool(uint32_t slot)>;

// The ranking every source ends with, from the pixels it counted per face: each face's pixels count for its
// three corners (`corners`, 3 per face; a face whose first corner is kNone is free and skipped), a corner
// being vertex `slot_of[corner]`, or the slot itself when `slot_of` is empty; then the leaves of `mesh`'s
// hierarchy that pass `can_split`, most pixels first (ties: lower slot first). `vertex_pixels` is working
// space kept between calls.
void rank_by_area(std::span<const uint64_t> face_pixels, std::span<const uint32_t> corners,
                  std::span<const uint32_t> slot_of, const SelectiveMesh& mesh, const CanSplit& can_split,
                  std::vector<uint64_t>& vertex_pixels, std::vector<VertexArea>& ranked);

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
