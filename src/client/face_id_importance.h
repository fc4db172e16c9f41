// cheng-ooi 2008 §4.2's importance (importance.h) from a face-id frame drawn elsewhere: the browser's WebGL
// draws the mesh's triangles with face slot + 1 as their colour (24 bits in RGB, 0 = background), reads the
// pixels back and hands them over every few frames (cheng-ooi did the same on the GPU). rank() counts the
// last frame's pixels per face and credits each live face's three corners, as the native
// source (screen_importance.h) does with its software renderer's face-id buffer. A frame drawn a few
// frames ago may name face slots the mesh has freed or reused since: a freed one counts for nothing, a
// reused one for its new corners, a ranking heuristic only.
// Shared with the browser build: no renderer, single-threaded.
#pragma once
#include <cstdint>
#include <span>
#include <vector>

#include "client/importance.h"

namespace pms::client {

class FaceIdImportance : public ImportanceSource {
 public:
  // The face-id frame: 4 bytes (RGBA) per pixel, width * height of them, face slot + 1 in R (low byte), G,
  // B (high byte). pms::Error when `rgba` is not width * height * 4 bytes, or over 4096 x 4096 pixels.
  void set_face_ids(std::span<const uint8_t> rgba, uint32_t width, uint32_t height);
  bool has_face_ids() const { return frames_ > 0; }
  uint64_t frames() const { return frames_; }

  const std::vector<VertexArea>& rank(const SelectiveMesh& mesh, const ViewParams& view,
                                      const CanSplit& can_split) override;

 private:
  std::vector<uint32_t> ids_;  // the last frame's face ids (slot + 1) where a face shows
  std::vector<uint64_t> face_pixels_, vertex_pixels_;
  std::vector<VertexArea> ranked_;
  uint64_t frames_ = 0;
};

}  // namespace pms::client
