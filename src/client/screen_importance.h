// cheng-ooi 2008 §4.2's importance (importance.h) measured with the software renderer: the front ranked by
// the screen area of each vertex's faces in the renderer's triangle-id buffer. A vertex none of whose faces
// shows (outside the frustum, behind the camera, hidden, back-facing seen edge-on) has no area and is not
// ranked. The native build's source; the browser's measures the same in WebGL.
#pragma once
#include <cstdint>
#include <vector>

#include "client/importance.h"
#include "common/camera.h"
#include "render/render.h"
#include "spm/selective_mesh.h"

namespace pms::client {

// Keeps its renderer and buffers between frames, so ranking along a path allocates nothing once warm.
class ScreenImportance : public ImportanceSource {
 public:
  // The frames are drawn without shading (face ids and depth only).
  explicit ScreenImportance(const RenderOptions& options = {}) : options_(options) { options_.shade = false; }

  // Renders `mesh` as `view` sees it and ranks its front from the face ids drawn (importance.h).
  const std::vector<VertexArea>& rank(const SelectiveMesh& mesh, const ViewParams& view,
                                      const CanSplit& can_split = {}) override;

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
