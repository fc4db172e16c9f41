#include "bench/image_quality.h"

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

std::string psnr_text(double psnr) { return std::isinf(psnr) ? "inf" : fixed(psnr, 2); }
double psnr_json(double psnr) { return std::isinf(psnr) ? kPsnrIdenticalJson : psnr; }

}  // namespace pms::bench
