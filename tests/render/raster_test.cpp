// Coverage, fill rule, depth order and near-plane clipping of the rasterizer, on scenes small enough to
// know every pixel by hand (render_fixtures.h: square_view maps z = 0 straight onto the pixel grid).
#include <gtest/gtest.h>
#include <cstring>
#include <random>

#include "common/error.h"
#include "render/render.h"
#include "render_fixtures.h"
#include "spm/vertex_id.h"

namespace pms {
namespace {

using test::ScreenMesh;
using test::square_view;

// Covered pixels of `face` as a string of '#'/'.' rows, for readable failure messages.
std::string coverage(const Image& image, uint32_t face) {
  std::string out;
  for (uint32_t y = 0; y < image.height; ++y) {
    for (uint32_t x = 0; x < image.width; ++x) out += image.face_id[y * image.width + x] == face ? '#' : '.';
    out += '\n';
  }
  return out;
}

std::string expected(uint32_t n, const std::function<bool(uint32_t, uint32_t)>& inside) {
  std::string out;
  for (uint32_t y = 0; y < n; ++y) {
    for (uint32_t x = 0; x < n; ++x) out += inside(x, y) ? '#' : '.';
    out += '\n';
  }
  return out;
}

TEST(Raster, KnownTriangleCoversKnownPixels) {
  // Screen (0,0) (8,0) (0,8): pixel (x, y) has its centre inside when x + y + 1 < 8. Centres on the
  // hypotenuse (x + y = 7) belong to the right/bottom edge, which does not own them (top-left rule).
  const uint32_t n = 8;
  ScreenMesh m;
  m.add_triangle(m.add_vertex(0, 0, n), m.add_vertex(8, 0, n), m.add_vertex(0, 8, n));
  const Image image = render(m.mesh(), square_view(n));
  EXPECT_EQ(coverage(image, 0), expected(n, [](uint32_t x, uint32_t y) { return x + y < 7; }));
  EXPECT_EQ(test::count_face(image, 0), 28u);
  for (size_t p = 0; p < size_t(n) * n; ++p) {
    const uint8_t* rgb = &image.rgb[3 * p];
    if (image.face_id[p] == 0) {
      // Facing the headlight: full intensity, the default light grey.
      EXPECT_EQ(rgb[0], 200);
      EXPECT_EQ(rgb[1], 200);
      EXPECT_EQ(rgb[2], 200);
      EXPECT_LT(image.depth[p], 1.0f);
      EXPECT_GT(image.depth[p], -1.0f);
    } else {
      EXPECT_EQ(image.face_id[p], kNone);
      EXPECT_EQ(image.depth[p], 1.0f);
      const RenderOptions defaults;
      for (int k = 0; k < 3; ++k) EXPECT_EQ(rgb[k], defaults.background[k]);
    }
  }
}

TEST(Raster, PixelCentresOnEdgesFollowTheTopLeftRule) {
  // Corners on pixel centres: (0.5,0.5) (6.5,0.5) (0.5,6.5). The top edge (y = 0.5) and the left edge
  // (x = 0.5) own their centres, the hypotenuse (x + y = 7) does not: pixels x + y <= 5.
  // The other half of the square, (6.5,0.5) (6.5,6.5) (0.5,6.5), gets the hypotenuse but not its right
  // (x = 6.5) or bottom (y = 6.5) edge: pixels x, y <= 5 with x + y >= 6. Together: the 6x6 square once.
  const uint32_t n = 8;
  for (const bool reversed : {false, true}) {  // winding must not matter: back faces are drawn
    ScreenMesh m;
    const uint32_t a = m.add_vertex(0.5f, 0.5f, n), b = m.add_vertex(6.5f, 0.5f, n), c = m.add_vertex(0.5f, 6.5f, n),
                   d = m.add_vertex(6.5f, 6.5f, n);
    if (reversed) {
      m.add_triangle(a, c, b);
      m.add_triangle(b, c, d);
    } else {
      m.add_triangle(a, b, c);
      m.add_triangle(b, d, c);
    }
    const Image image = render(m.mesh(), square_view(n));
    EXPECT_EQ(coverage(image, 0), expected(n, [](uint32_t x, uint32_t y) { return x + y <= 5; })) << reversed;
    EXPECT_EQ(coverage(image, 1), expected(n, [](uint32_t x, uint32_t y) { return x <= 5 && y <= 5 && x + y >= 6; }))
        << reversed;
  }
}

// How many of `mesh`'s faces cover each pixel, by rendering every face alone (the id buffer of a full
// render cannot show double cover: the second triangle loses the depth tie).
std::vector<int> cover_counts(const std::vector<float>& positions, const std::vector<uint32_t>& indices,
                              const ViewParams& view) {
  Renderer renderer;
  Image image;
  std::vector<int> counts(size_t(view.camera.width) * view.camera.height, 0);
  for (size_t f = 0; f < indices.size() / 3; ++f) {
    const RenderMesh one{positions, std::span<const uint32_t>(&indices[3 * f], 3), {}};
    renderer.render(one, view, image);
    for (size_t p = 0; p < counts.size(); ++p) counts[p] += image.face_id[p] != kNone;
  }
  return counts;
}

TEST(Raster, FanAroundAPixelCentreCoversItOnce) {
  // 8 triangles around a vertex on a pixel centre, with horizontal, vertical and diagonal edges through
  // other centres: every pixel of the fan's square is covered exactly once.
  const uint32_t n = 10;
  ScreenMesh m;
  const uint32_t centre = m.add_vertex(4.5f, 4.5f, n);
  const float ring[8][2] = {{8.5f, 4.5f}, {8.5f, 8.5f}, {4.5f, 8.5f}, {0.5f, 8.5f},
                            {0.5f, 4.5f}, {0.5f, 0.5f}, {4.5f, 0.5f}, {8.5f, 0.5f}};
  uint32_t ids[8];
  for (int i = 0; i < 8; ++i) ids[i] = m.add_vertex(ring[i][0], ring[i][1], n);
  for (int i = 0; i < 8; ++i) m.add_triangle(centre, ids[i], ids[(i + 1) % 8]);
  const std::vector<int> counts = cover_counts(m.positions, m.indices, square_view(n));
  for (uint32_t y = 0; y < n; ++y)
    for (uint32_t x = 0; x < n; ++x) {
      // The square's top and left sides own their centres, its bottom and right sides do not.
      const bool inside = x <= 7 && y <= 7;
      EXPECT_EQ(counts[y * n + x], inside ? 1 : 0) << x << "," << y;
    }
}

TEST(Raster, JitteredGridCoversEveryPixelOnce) {
  // A perturbed grid, bigger than the viewport, seen in perspective: shared edges in every direction,
  // some corners snapped onto pixel centres. No cracks, no double cover.
  const uint32_t n = 40, cells = 9;
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> jitter(-0.15f, 0.15f), height(-0.02f, 0.02f);
  std::vector<float> positions;
  std::vector<uint32_t> indices;
  const float lo = -1.3f, step = 2.6f / cells;
  for (uint32_t j = 0; j <= cells; ++j)
    for (uint32_t i = 0; i <= cells; ++i) {
      const bool border = i == 0 || j == 0 || i == cells || j == cells;
      float x = lo + step * float(i) + (border ? 0 : jitter(rng) * step);
      float y = lo + step * float(j) + (border ? 0 : jitter(rng) * step);
      float z = border ? 0 : height(rng);
      if ((i + j) % 5 == 0 && !border) {  // onto a pixel centre of the z = 0 plane
        x = (std::floor((x + 1) * n / 2) + 0.5f) * 2 / n - 1;
        y = 1 - (std::floor((1 - y) * n / 2) + 0.5f) * 2 / n;
        z = 0;
      }
      positions.insert(positions.end(), {x, y, z});
    }
  for (uint32_t j = 0; j < cells; ++j)
    for (uint32_t i = 0; i < cells; ++i) {
      const uint32_t a = j * (cells + 1) + i, b = a + 1, c = a + cells + 2, d = a + cells + 1;
      if ((i + j) % 2) indices.insert(indices.end(), {a, b, c, a, c, d});
      else indices.insert(indices.end(), {a, b, d, b, c, d});
    }
  const ViewParams view = square_view(n);
  const std::vector<int> counts = cover_counts(positions, indices, view);
  for (size_t p = 0; p < counts.size(); ++p) EXPECT_EQ(counts[p], 1) << "pixel " << p % n << "," << p / n;
  // Drawn together, nothing of the background shows through.
  const Image image = render({positions, indices, {}}, view);
  for (const uint32_t id : image.face_id) EXPECT_NE(id, kNone);
}

TEST(Raster, NearTriangleOccludesFarOneInEitherOrder) {
  const uint32_t n = 16;
  // Far: a big triangle at z = -0.3 (red); near: a smaller one at z = 0.3 (green) over the middle.
  const std::vector<float> far_tri = {-1, -1, -0.3f, 1, -1, -0.3f, 0, 1, -0.3f};
  const std::vector<float> near_tri = {-0.4f, -0.4f, 0.3f, 0.4f, -0.4f, 0.3f, 0, 0.4f, 0.3f};
  const uint8_t red[4] = {255, 0, 0, 255}, green[4] = {0, 255, 0, 255};
  for (const bool near_first : {false, true}) {
    std::vector<float> positions;
    std::vector<uint8_t> colors;
    for (const auto* tri : {near_first ? &near_tri : &far_tri, near_first ? &far_tri : &near_tri}) {
      positions.insert(positions.end(), tri->begin(), tri->end());
      const uint8_t* c = tri == &near_tri ? green : red;
      for (int v = 0; v < 3; ++v) colors.insert(colors.end(), c, c + 4);
    }
    const std::vector<uint32_t> indices = {0, 1, 2, 3, 4, 5};
    const Image image = render({positions, indices, colors}, square_view(n));
    const uint32_t near_face = near_first ? 0 : 1;
    const size_t centre = (n / 2) * n + n / 2;
    EXPECT_EQ(image.face_id[centre], near_face) << near_first;
    EXPECT_EQ(image.rgb[3 * centre + 0], 0);
    EXPECT_EQ(image.rgb[3 * centre + 1], 255);
    // The near face shows wherever it covers anything, and is nearer than the far face everywhere.
    const Image near_alone = render({near_tri, std::span<const uint32_t>(indices).first(3), {}}, square_view(n));
    size_t shown = 0;
    for (size_t p = 0; p < size_t(n) * n; ++p)
      if (near_alone.face_id[p] != kNone) {
        EXPECT_EQ(image.face_id[p], near_face) << p;
        ++shown;
      }
    EXPECT_GT(shown, 10u);
  }
}

TEST(Raster, DepthTiesGoToTheLowerFaceIndex) {
  const uint32_t n = 8;
  const std::vector<float> positions = {-1, -1, 0, 1, -1, 0, 0, 1, 0, -1, -1, 0, 1, -1, 0, 0, 1, 0};
  const std::vector<uint8_t> colors = {255, 0, 0,   255, 255, 0, 0,   255, 255, 0, 0,   255,
                                       0,   0, 255, 255, 0,   0, 255, 255, 0,   0, 255, 255};
  const std::vector<uint32_t> indices = {3, 4, 5, 0, 1, 2};  // face 0 is the blue copy
  const Image image = render({positions, indices, colors}, square_view(n));
  size_t covered = 0;
  for (size_t p = 0; p < size_t(n) * n; ++p) {
    if (image.face_id[p] == kNone) continue;
    ++covered;
    EXPECT_EQ(image.face_id[p], 0u);
    EXPECT_EQ(image.rgb[3 * p + 2], 255);
  }
  EXPECT_GT(covered, 20u);
}

TEST(Raster, TriangleCrossingTheCameraPlaneIsClippedNotDroppedOrExploded) {
  // A floor triangle under the eye that reaches behind it (corner C at z = +5, w < 0). Without
  // near-plane clipping C would project through the eye to the wrong side of the screen.
  Camera camera;
  camera.eye[0] = 0, camera.eye[1] = 0, camera.eye[2] = 0;
  camera.target[0] = 0, camera.target[1] = 0, camera.target[2] = -1;
  camera.fovy_deg = 90;
  camera.width = 64, camera.height = 48;
  const std::vector<float> positions = {-3, -1, -3, 3, -1, -3, 0, -1, 5};
  const std::vector<uint32_t> indices = {0, 1, 2};
  const float lo[3] = {-3, -1, -3}, hi[3] = {3, -1, 5};
  const ViewParams view = make_view(camera, lo, hi);
  const Image image = render({positions, indices, {}}, view);

  size_t checked = 0, covered = 0;
  test::for_each_pixel_ray(camera, positions, 1e-3, [&](const test::PixelRay& ray) {
    const uint32_t x = ray.x, y = ray.y;
    const size_t p = ray.pixel;
    const int hit = ray.hit;
    if (y < camera.height / 2) {
      EXPECT_EQ(image.face_id[p], kNone) << "above the horizon: " << x << "," << y;
    }
    if (hit == 0) return;
    ++checked;
    EXPECT_EQ(image.face_id[p], hit > 0 ? 0u : kNone) << x << "," << y;
    if (hit > 0 && image.face_id[p] == 0) {
      ++covered;
      // NDC depth of eye distance t * |forward component| (forward = -z, dir z = -1).
      const double d = ray.t, n = view.near_plane, f = view.far_plane;
      const double z_ndc = (f + n) / (f - n) - 2 * f * n / ((f - n) * d);
      EXPECT_NEAR(image.depth[p], z_ndc, 1e-4) << x << "," << y;
    }
  });
  EXPECT_GT(checked, size_t(camera.width) * camera.height * 9 / 10);
  EXPECT_GT(covered, 500u);
  // The bottom row looks down at 45 degrees and meets the floor one unit ahead: covered across the width
  // of the triangle there.
  EXPECT_EQ(image.face_id[size_t(camera.height - 1) * camera.width + camera.width / 2], 0u);
}

TEST(Raster, NearPlaneCutsWhatIsCloserThanIt) {
  // near/far from a box 2..10 units ahead: near ~ 1.98. A floor triangle from 0.5 to 8 units ahead is cut
  // at the near plane: the pixels that see it closer than near show nothing, the rest show it.
  Camera camera;
  camera.eye[0] = 0, camera.eye[1] = 0, camera.eye[2] = 0;
  camera.target[0] = 0, camera.target[1] = 0, camera.target[2] = -1;
  camera.fovy_deg = 90;
  camera.width = 48, camera.height = 48;
  const float lo[3] = {-1, -1, -10}, hi[3] = {1, 1, -2};
  const ViewParams view = make_view(camera, lo, hi);
  ASSERT_GT(view.near_plane, 1.9f);
  const std::vector<float> positions = {-3, -1, -0.5f, 3, -1, -0.5f, 0, -1, -8};
  const std::vector<uint32_t> indices = {0, 1, 2};
  const Image image = render({positions, indices, {}}, view);
  size_t cut = 0, shown = 0;
  test::for_each_pixel_ray(camera, positions, 1e-3, [&](const test::PixelRay& ray) {
    if (ray.hit != 1) return;
    const uint32_t id = image.face_id[ray.pixel];
    if (ray.t < view.near_plane * 0.99) {
      EXPECT_EQ(id, kNone) << ray.x << "," << ray.y << " at distance " << ray.t;
      ++cut;
    } else if (ray.t > view.near_plane * 1.01) {
      EXPECT_EQ(id, 0u) << ray.x << "," << ray.y << " at distance " << ray.t;
      ++shown;
    }
  });
  EXPECT_GT(cut, 50u);
  EXPECT_GT(shown, 50u);
}

TEST(Raster, HugeTriangleIsClippedToTheGuardBand) {
  // A floor triangle whose near corners project millions of pixels off screen: cut at the guard band,
  // it still covers exactly the pixels that see it.
  Camera camera;
  camera.eye[0] = 0, camera.eye[1] = 10, camera.eye[2] = 0;
  camera.target[0] = 0, camera.target[1] = 10, camera.target[2] = -1;
  camera.fovy_deg = 60;
  camera.width = 64, camera.height = 48;
  const std::vector<float> positions = {-1e8f, 0, -20, 1e8f, 0, -20, 0, 0, -1e5f};
  const std::vector<uint32_t> indices = {0, 1, 2};
  const float lo[3] = {-1e8f, 0, -1e5f}, hi[3] = {1e8f, 10, -20};
  const ViewParams view = make_view(camera, lo, hi);
  const Image image = render({positions, indices, {}}, view);
  size_t covered = 0;
  test::for_each_pixel_ray(camera, positions, 1e-4, [&](const test::PixelRay& ray) {
    if (ray.hit == 0) return;
    const uint32_t id = image.face_id[ray.pixel];
    EXPECT_EQ(id, ray.hit > 0 ? 0u : kNone) << ray.x << "," << ray.y;
    covered += id == 0;
  });
  EXPECT_GT(covered, 500u);
}

TEST(Raster, WholeMeshBehindTheEyeDrawsNothing) {
  const std::vector<float> positions = {-1, -1, 2, 1, -1, 2, 0, 1, 2};
  const std::vector<uint32_t> indices = {0, 1, 2};
  const Image image = render({positions, indices, {}}, square_view(8));
  for (const uint32_t id : image.face_id) EXPECT_EQ(id, kNone);
  EXPECT_TRUE(visible_faces(image).empty());
}

TEST(Raster, RejectsMalformedArrays) {
  const std::vector<float> positions = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  const std::vector<uint32_t> bad_index = {0, 1, 3};
  EXPECT_THROW(render({positions, bad_index, {}}, square_view(8)), Error);
  const std::vector<float> ragged = {0, 0, 0, 1};
  const std::vector<uint32_t> indices = {0, 0, 0};
  EXPECT_THROW(render({ragged, indices, {}}, square_view(8)), Error);
  const std::vector<uint8_t> short_colors = {1, 2, 3};
  EXPECT_THROW(render({positions, indices, short_colors}, square_view(8)), Error);
  const std::vector<uint32_t> partial_face = {0, 1};
  EXPECT_THROW(render({positions, partial_face, {}}, square_view(8)), Error);
}

TEST(Raster, EmptyMeshIsBackground) {
  const Image image = render({}, square_view(5));
  ASSERT_EQ(image.rgb.size(), 75u);
  const RenderOptions defaults;
  for (size_t p = 0; p < 25; ++p) {
    EXPECT_EQ(image.face_id[p], kNone);
    for (int k = 0; k < 3; ++k) EXPECT_EQ(image.rgb[3 * p + k], defaults.background[k]);
  }
}

}  // namespace
}  // namespace pms
