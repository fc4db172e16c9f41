// Image metrics of cheng-ooi 2008 Table 2 (PSNR and error pixels of a frame against the reference frame
// of the full-resolution mesh), and the visible-face count every experiment reads off the id buffer.
#include <cmath>
#include <limits>

#include "common/error.h"
#include "render/render.h"
#include "spm/vertex_id.h"

namespace pms {

ImageMetrics compare_images(const Image& a, const Image& b) {
  if (a.width != b.width || a.height != b.height)
    fail("compare", "images differ in size (" + std::to_string(a.width) + "x" + std::to_string(a.height) + " vs " +
                        std::to_string(b.width) + "x" + std::to_string(b.height) + ")");
  const size_t pixels = size_t(a.width) * a.height;
  if (a.rgb.size() != 3 * pixels || b.rgb.size() != 3 * pixels) fail("compare", "image buffer has the wrong size");
  ImageMetrics metrics;
  uint64_t squared_error = 0;  // exact: at most 3 * 255^2 per pixel
  for (size_t p = 0; p < pixels; ++p) {
    const uint8_t* x = &a.rgb[3 * p];
    const uint8_t* y = &b.rgb[3 * p];
    uint32_t pixel_error = 0;
    for (int k = 0; k < 3; ++k) {
      const int d = int(x[k]) - int(y[k]);
      pixel_error += uint32_t(d * d);
    }
    squared_error += pixel_error;
    metrics.error_pixels += pixel_error != 0;
  }
  if (pixels == 0) return {std::numeric_limits<double>::infinity(), 0, 0};
  const double mse = double(squared_error) / double(3 * pixels);
  metrics.psnr = mse == 0 ? std::numeric_limits<double>::infinity() : 10.0 * std::log10(255.0 * 255.0 / mse);
  metrics.error_fraction = double(metrics.error_pixels) / double(pixels);
  return metrics;
}

std::vector<uint32_t> visible_faces(const Image& image) {
  uint32_t max_id = 0;
  bool any = false;
  for (const uint32_t id : image.face_id)
    if (id != kNone) {
      max_id = std::max(max_id, id);
      any = true;
    }
  if (!any) return {};
  // A mark per face id up to the largest seen: linear, no sort of the million ids of a frame.
  std::vector<uint8_t> seen(size_t(max_id) + 1, 0);
  for (const uint32_t id : image.face_id)
    if (id != kNone) seen[id] = 1;
  std::vector<uint32_t> faces;
  for (uint32_t f = 0; f <= max_id; ++f)
    if (seen[f]) faces.push_back(f);
  return faces;
}

}  // namespace pms
