// What the image-quality experiments share (the refine group's quality table, E6 and E8 of the receiver
// group): the three viewpoints, far, mid and close, from the model's own camera paths; a mesh as the
// renderer takes it; PSNR as the tables and the JSON write it.
#pragma once
#include <string>
#include <vector>

#include "common/camera.h"
#include "render/render.h"
#include "spm/hierarchy.h"
#include "spm/selective_mesh.h"

namespace pms::bench {

struct Viewpoint {
  const char* label;  // "far", "mid", "close"
  Camera camera;
};

// Far and close are the 3-frame zoom path's ends (6 framing distances away, and 2 % of the box diagonal from
// the surface); mid is the first orbit view moved halfway to its target, the sender group's E5 close view.
std::vector<Viewpoint> quality_viewpoints(const ModelData& model);

RenderMesh as_render(const MeshArrays& mesh);

// The panels left to right, as tall as the first, with a gap of the renderer's background colour.
Image side_by_side(const std::vector<Image>& panels);

// "inf" for identical images, else two decimals; JSON has no infinity (kPsnrIdenticalJson).
std::string psnr_text(double psnr);
double psnr_json(double psnr);

}  // namespace pms::bench
