#include "bench/image_quality.h"

#include <algorithm>
#include <cmath>

#include "apps/camera_path.h"
#include "bench/report.h"
#include "bench/split_record_bits.h"

namespace pms::bench {
using app::make_camera_path;
using app::PathKind;
using app::PathOptions;

std::vector<Viewpoint> quality_viewpoints(const ModelData& model) {
  PathOptions options;
  options.frames = 3;
  const std::vector<Camera> zoom = make_camera_path(PathKind::zoom, model, options);
  return {{"far", zoom[0]}, {"mid", close_view(model)}, {"close", zoom[2]}};
}

RenderMesh as_render(const MeshArrays& mesh) { return {mesh.positions, mesh.indices, mesh.colors}; }

Image side_by_side(const std::vector<Image>& panels) {
  constexpr uint32_t kGap = 8;  // pixels between the panels
  Image out;
  out.height = panels.front().height;
  for (const Image& p : panels) out.width += p.width;
  out.width += kGap * uint32_t(panels.size() - 1);
  const RenderOptions defaults;
  out.rgb.resize(size_t(out.width) * out.height * 3);
  for (size_t p = 0; p < out.rgb.size(); p += 3) std::copy(defaults.background, defaults.background + 3, &out.rgb[p]);
  uint32_t x0 = 0;
  for (const Image& p : panels) {
    for (uint32_t y = 0; y < p.height; ++y)
      std::copy_n(&p.rgb[(size_t(y) * p.width) * 3], size_t(p.width) * 3, &out.rgb[(size_t(y) * out.width + x0) * 3]);
    x0 += p.width + kGap;
  }
  return out;
}

std::string psnr_text(double psnr) { return std::isinf(psnr) ? "inf" : fixed(psnr, 2); }
double psnr_json(double psnr) { return std::isinf(psnr) ? kPsnrIdenticalJson : psnr; }

}  // namespace pms::bench
