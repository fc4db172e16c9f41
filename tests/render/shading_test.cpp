// Shading (headlight Lambert, ambient, per-vertex colours, perspective-correct interpolation) and the
// guarantee the experiments rely on: the same bits for any number of threads.
#include <gtest/gtest.h>
#include <cmath>
#include <cstring>

#include "common/error.h"
#include "io/shapes.h"
#include "render/render.h"
#include "render_fixtures.h"
#include "spm/vertex_id.h"

namespace pms {
namespace {

using test::square_view;

uint8_t expected_shade(uint8_t base, double cosine) {
  const float intensity = 0.15f + 0.85f * float(cosine);
  return uint8_t(std::min(float(base) * intensity + 0.5f, 255.0f));
}

TEST(Shading, LambertFromTheHeadlightWithAmbient) {
  // A square tilted 60 degrees away from the view direction: |cos| = 0.5.
  const float c = std::cos(float(M_PI) / 3), s = std::sin(float(M_PI) / 3);
  const std::vector<float> positions = {-0.5f, -0.5f * c, -0.5f * s, 0.5f,  -0.5f * c, -0.5f * s,
                                        0.5f,  0.5f * c,  0.5f * s,  -0.5f, 0.5f * c,  0.5f * s};
  const std::vector<uint32_t> indices = {0, 1, 2, 0, 2, 3};
  const Image image = render({positions, indices, {}}, square_view(16));
  const size_t centre = 8 * 16 + 8;
  ASSERT_NE(image.face_id[centre], kNone);
  EXPECT_NEAR(image.rgb[3 * centre], expected_shade(200, 0.5), 1);

  RenderOptions options;
  options.ambient = 1;  // all ambient: the plain surface colour
  options.surface[0] = 10, options.surface[1] = 20, options.surface[2] = 30;
  const Image flat = render({positions, indices, {}}, square_view(16), options);
  EXPECT_EQ(flat.rgb[3 * centre + 0], 10);
  EXPECT_EQ(flat.rgb[3 * centre + 1], 20);
  EXPECT_EQ(flat.rgb[3 * centre + 2], 30);
}

// RenderOptions::light: a fixed light (a sun) instead of the headlight, whatever its length; all zero is the
// headlight.
TEST(Shading, LambertFromAFixedLight) {
  // A square facing the camera (normal +z, view along -z): the headlight gives |cos| = 1.
  const std::vector<float> positions = {-0.5f, -0.5f, 0, 0.5f, -0.5f, 0, 0.5f, 0.5f, 0, -0.5f, 0.5f, 0};
  const std::vector<uint32_t> indices = {0, 1, 2, 0, 2, 3};
  const size_t centre = 8 * 16 + 8;
  const Image headlight = render({positions, indices, {}}, square_view(16));
  ASSERT_NE(headlight.face_id[centre], kNone);
  EXPECT_NEAR(headlight.rgb[3 * centre], expected_shade(200, 1), 1);
  RenderOptions options;
  options.light[0] = 0, options.light[1] = 0, options.light[2] = 0;
  EXPECT_EQ(render({positions, indices, {}}, square_view(16), options).rgb, headlight.rgb);
  // Light 60 degrees off the normal, given at another length: |cos| = 0.5.
  options.light[0] = 3 * std::sin(float(M_PI) / 3), options.light[2] = -3 * std::cos(float(M_PI) / 3);
  const Image sun = render({positions, indices, {}}, square_view(16), options);
  EXPECT_NEAR(sun.rgb[3 * centre], expected_shade(200, 0.5), 1);
  EXPECT_EQ(sun.face_id, headlight.face_id) << "light changes colours only";
}

TEST(Shading, BackFacesLookLikeFrontFaces) {
  const Mesh sphere = make_sphere(12, 24);
  Mesh inside_out = sphere;
  for (size_t f = 0; f < inside_out.face_count(); ++f)
    std::swap(inside_out.indices[3 * f + 1], inside_out.indices[3 * f + 2]);
  Camera camera;
  camera.width = 64, camera.height = 48;
  const float lo[3] = {-1, -1, -1}, hi[3] = {1, 1, 1};
  const ViewParams view = make_view(camera, lo, hi);
  const Image a = render({sphere.positions, sphere.indices, {}}, view);
  const Image b = render({inside_out.positions, inside_out.indices, {}}, view);
  EXPECT_EQ(a.rgb, b.rgb);
  EXPECT_EQ(a.face_id, b.face_id);
}

TEST(Shading, VertexColoursArePerspectiveCorrect) {
  // A floor triangle receding from a camera looking down at 45 degrees, with a different colour per
  // corner: each pixel must show the colour of the surface point it sees (interpolated in 3D), which
  // affine screen-space interpolation gets wrong by tens of levels here.
  Camera camera;
  camera.eye[0] = 0, camera.eye[1] = 0, camera.eye[2] = 0;
  camera.target[0] = 0, camera.target[1] = -1, camera.target[2] = -1;
  camera.fovy_deg = 60;
  camera.width = 48, camera.height = 48;
  const std::vector<float> positions = {-1.5f, -1, -1, 1.5f, -1, -1, 0, -1, -12};
  const std::vector<uint8_t> colors = {0, 0, 255, 255, 255, 0, 0, 255, 0, 255, 0, 255};
  const std::vector<uint32_t> indices = {0, 1, 2};
  const float lo[3] = {-1.5f, -1, -12}, hi[3] = {1.5f, -1, -1};
  const ViewParams view = make_view(camera, lo, hi);
  const Image image = render({positions, indices, colors}, view);
  const double cosine = std::sqrt(0.5);  // floor normal (0, 1, 0) against forward (0, -1, -1) / sqrt 2
  size_t checked = 0;
  int worst = 0;
  test::for_each_pixel_ray(camera, positions, 1e-3, [&](const test::PixelRay& ray) {
    if (ray.hit != 1) return;
    const size_t p = ray.pixel;
    ASSERT_EQ(image.face_id[p], 0u) << ray.x << "," << ray.y;
    for (int k = 0; k < 3; ++k) {
      double want = 0;  // vertex colours are lit (and rounded) at the vertices, then interpolated
      for (int v = 0; v < 3; ++v) want += ray.bary[v] * expected_shade(colors[4 * v + k], cosine);
      const int diff = std::abs(int(image.rgb[3 * p + k]) - int(std::lround(want)));
      worst = std::max(worst, diff);
      EXPECT_LE(diff, 1) << ray.x << "," << ray.y << " channel " << k;
    }
    ++checked;
  });
  EXPECT_GT(checked, 300u);
  EXPECT_LE(worst, 1);
}

TEST(Shading, AreaWeightedNormalsOfTheDrawnMesh) {
  // A vertex shared by a big face towards the viewer and a small face edge-on: its normal follows the
  // big face (area weighting), so the big face's corner there stays at full intensity. Averaging unit
  // normals instead would tilt it 45 degrees and darken that corner by a quarter.
  const std::vector<float> positions = {-1, -1, 0,     1, -1, 0, 0, 1, 0,  // big, facing +z
                                        1,  -1, -0.01f};                   // small, along -z from (1,-1,0)
  const std::vector<uint32_t> indices = {0, 1, 2, 1, 3, 2};
  const Image image = render({positions, indices, {}}, square_view(32));
  const Image alone = render({positions, std::span<const uint32_t>(indices).first(3), {}}, square_view(32));
  const size_t p = size_t(30) * 32 + 28;  // near the bottom-right corner (vertex 1) of the big face
  ASSERT_EQ(image.face_id[p], 0u);
  EXPECT_NEAR(image.rgb[3 * p], alone.rgb[3 * p], 2);
  EXPECT_EQ(alone.rgb[3 * p], 200);
}

void expect_identical(const Image& a, const Image& b, const char* what) {
  ASSERT_EQ(a.width, b.width);
  ASSERT_EQ(a.height, b.height);
  EXPECT_EQ(a.rgb, b.rgb) << what;
  EXPECT_EQ(a.face_id, b.face_id) << what;
  ASSERT_EQ(a.depth.size(), b.depth.size());
  EXPECT_EQ(std::memcmp(a.depth.data(), b.depth.data(), a.depth.size() * sizeof(float)), 0) << what;
}

TEST(Render, SameBitsForAnyThreadCount) {
  const Mesh terrain = make_terrain(120000);
  float lo[3] = {1e30f, 1e30f, 1e30f}, hi[3] = {-1e30f, -1e30f, -1e30f};
  for (size_t v = 0; v < terrain.vertex_count(); ++v)
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], terrain.positions[3 * v + k]);
      hi[k] = std::max(hi[k], terrain.positions[3 * v + k]);
    }
  // Two views: one over the whole terrain, one from inside it (near-plane and guard-band clipping).
  Camera overview, low;
  overview.eye[0] = 5000, overview.eye[1] = -4000, overview.eye[2] = 6000;
  overview.target[0] = 5000, overview.target[1] = 5000, overview.target[2] = 0;
  overview.up[0] = 0, overview.up[1] = 0, overview.up[2] = 1;
  overview.width = 300, overview.height = 200;
  low = overview;
  low.eye[0] = 3000, low.eye[1] = 3000, low.eye[2] = hi[2] * 0.6f;
  low.target[0] = 6000, low.target[1] = 7000, low.target[2] = 0;
  low.fovy_deg = 100;
  for (const Camera& camera : {overview, low}) {
    const ViewParams view = make_view(camera, lo, hi);
    const RenderMesh mesh{terrain.positions, terrain.indices, {}};
    RenderOptions one;
    one.threads = 1;
    const Image reference = render(mesh, view, one);
    EXPECT_GT(visible_faces(reference).size(), 1000u);
    Renderer renderer;  // reused across thread counts: scratch from a previous frame must not leak in
    for (const unsigned threads : {2u, 3u, 4u, 7u, 16u}) {
      RenderOptions options;
      options.threads = threads;
      Image image;
      renderer.render(mesh, view, image, options);
      expect_identical(reference, image, ("threads " + std::to_string(threads)).c_str());
    }
    // Without shading: the same ids and depths, and no colour (the renderer's buffers were shaded before).
    for (const unsigned threads : {1u, 3u}) {
      RenderOptions options;
      options.threads = threads;
      options.shade = false;
      Image ids;
      renderer.render(mesh, view, ids, options);
      EXPECT_TRUE(ids.rgb.empty());
      Image shaded_ids = reference;
      shaded_ids.rgb.clear();
      expect_identical(shaded_ids, ids, ("unshaded, threads " + std::to_string(threads)).c_str());
    }
  }
}

TEST(Render, UnshadedFramesStillRejectIndicesOutOfRange) {
  const std::vector<float> positions = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  const std::vector<uint32_t> indices = {0, 1, 3};
  RenderOptions options;
  options.shade = false;
  Camera camera;
  camera.width = camera.height = 8;
  const float lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
  EXPECT_THROW(render(RenderMesh{positions, indices, {}}, make_view(camera, lo, hi), options), Error);
}

TEST(Render, VisibleFacesAreTheDistinctIds) {
  Image image;
  image.width = 3, image.height = 2;
  image.face_id = {7, kNone, 2, 7, 2, 9};
  EXPECT_EQ(visible_faces(image), (std::vector<uint32_t>{2, 7, 9}));
}

}  // namespace
}  // namespace pms
