// cheng-ooi 2008 §4.2's importance for a receiver-driven client: the vertices of its front ranked by the
// screen area of their incident faces, measured from the software renderer's triangle-id buffer, so the
// splits that change the most pixels are asked for first. A vertex none of whose faces shows (outside the
// frustum, behind the camera, hidden, back-facing seen edge-on) has no area and is not ranked.
// Shared with the browser build: single-threaded, no std::ranges algorithms, std::format or coroutines
// (render with RenderOptions::threads = 1 there).
#pragma once
#include <cstdint>
#include <functional>
#include <vector>

#include "common/camera.h"
#include "render/render.h"
#include "spm/selective_mesh.h"

namespace pms::client {

struct VertexArea {
  uint32_t slot = 0;    // the vertex: a slot of the client's hierarchy
  uint64_t pixels = 0;  // pixels of its incident faces (each face's pixels count for its three corners)
};

// Whether a front vertex may be split: the caller knows which leaves the model refines further.
using CanSplit = std::function<bool(uint32_t slot)>;

// Keeps its renderer and buffers between frames, so ranking along a path allocates nothing once warm.
class ScreenImportance {
 public:
  // The frames are drawn without shading (face ids and depth only).
  explicit ScreenImportance(const RenderOptions& options = {}) : options_(options) { options_.shade = false; }

  // Renders `mesh` as `view` sees it and returns its active vertices that are leaves of the partial
  // hierarchy (and pass `can_split`, when given) with a non-zero area, most pixels first (ties: lower
  // slot first, so the order is deterministic).
  const std::vector<VertexArea>& rank(const SelectiveMesh& mesh, const ViewParams& view,
                                      const CanSplit& can_split = {});

  // Of the last rank(): the frame drawn (its face ids index the faces of mesh_arrays(); no rgb), and the pixels
  // some face covers.
  const Image& image() const { return image_; }
  const MeshArrays& mesh_arrays() const { return arrays_; }
  uint64_t covered_pixels() const { return covered_; }

 private:
  RenderOptions options_;
  Renderer renderer_;
  Image image_;
  MeshArrays arrays_;
  std::vector<uint64_t> face_pixels_, vertex_pixels_;  // per face / output vertex of arrays_
  std::vector<VertexArea> ranked_;
  uint64_t covered_ = 0;
};

}  // namespace pms::client
