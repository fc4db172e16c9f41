// The render layer: a deterministic software rasterizer (depth + smooth Lambert, triangle-id buffer),
// PNG output and the image metrics of cheng-ooi 2008 Table 2 (PSNR, error pixels). The images of the
// experiments come from here, so the same mesh and view give the same bytes on every run, whatever the
// thread count. Conventions (fill rule, shading, metric definitions) are in docs/internals.md, "Renderer".
#pragma once
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "common/camera.h"  // ViewParam"

namespace pms {

// A triangle mesh as flat arrays (not owned): io's Mesh and refine's MeshArrays both convert as
// {positions, indices, colors}.
struct RenderMesh {
  std::span<const float> positions;   // 3 per vertex
  std::span<const uint32_t> indices;  // 3 per face, CCW; back faces are drawn (and shaded) too
  std::span<const uint8_t> colors;    // 4 per vertex (RGBA8, alpha ignored), or empty: surface colour
};

struct RenderOptions {
  unsigned threads = 0;   // 0 = std::thread::hardware_concurrency(); never changes the image
  float ambient = 0.15f;  // intensity = ambient + (1 - ambient) * |n . light direction|
  // The direction the light shines along, in model space (it need not be unit length), as a sun over a
  // terrain; all zero: a headlight along the view direction.
  float light[3] = {0, 0, 0};
  uint8_t surface[3] = {200, 200, 200};  // when the mesh has no colors
  uint8_t background[3] = {40, 44, 52};
  // false: depth and face ids only, `rgb` left empty (no normals, lighting or colour writes) -- what a
  // visibility or importance pass needs, at about half the cost; the ids are those of a shaded frame.
  bool shade = true;
};

struct Image {
  uint32_t width = 0, height = 0;
  std::vector<uint8_t> rgb;       // 3 per pixel, row 0 at the top, linear (gamma-free) 8-bit; empty unless shaded
  std::vector<float> depth;       // NDC z in [-1, 1) of the visible surface; 1 where nothing was drawn
  std::vector<uint32_t> face_id;  // the face seen at the pixel (index into indices / 3), or kNone
};

// Keeps its scratch buffers between frames, so rendering a path costs no allocation after the first
// frame of a given size (use one per thread of the caller; render() itself is multithreaded).
class Renderer {
 public:
  Renderer();
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  // Draws `mesh` as seen by `view` (view_projection, near/far, camera width x height) into `out`,
  // resizing its buffers. Throws pms::Error for arrays of the wrong size or an index out of range.
  void render(const RenderMesh& mesh, const ViewParams& view, Image& out, const RenderOptions& options = {});

 private:
  struct Scratch;
  std::unique_ptr<Scratch> scratch_;
};

// One-shot convenience over Renderer.
Image render(const RenderMesh& mesh, const ViewParams& view, const RenderOptions& options = {});

// Writes the RGB8 image; throws pms::Error("PATH: ...") when the file cannot be written.
void save_png(const std::string& path, const Image& image);

// cheng-ooi 2008 Table 2: PSNR over the RGB channels (MSE over 3 * width * height samples, peak 255;
// +infinity for identical images), error pixels = pixels whose RGB differs at all, error fraction =
// error pixels / (width * height). Throws pms::Error when the sizes differ.
struct ImageMetrics {
  double psnr = 0;
  uint64_t error_pixels = 0;
  double error_fraction = 0;
};
ImageMetrics compare_images(const Image& a, const Image& b);

// JSON has no infinity: writers report the PSNR of identical images as this value.
constexpr double kPsnrIdenticalJson = 999;

// The distinct face ids in the id buffer, ascending (kNone excluded): what the experiments count as the
// visible faces of a frame.
std::vector<uint32_t> visible_faces(const Image& image);

}  // namespace pms
