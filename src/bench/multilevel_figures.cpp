#include "bench/multilevel_figures.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <vector>

#include "bench/image_quality.h"
#include "common/camera.h"
#include "io/mesh.h"
#include "multilevel/cluster.h"
#include "multilevel/dag.h"
#include "multilevel/local.h"
#include "multilevel/region.h"
#include "render/render.h"

namespace pms::bench {
namespace {

constexpr uint32_t kPanelPixels = 400;
// Fig. 1's LODs of the horse, in triangles.
constexpr std::array<uint64_t, 4> kPaperLodTriangles = {247, 665, 1519, 4350};
// Fig. 11: three clusterings, finest first, each a grid of N × N × N cells over the box; the paper's has
// 64, 16 and 4 triangles on a small non-manifold model, ours is coarser cells over a scan.
constexpr std::array<uint32_t, 3> kClusterGrids = {16, 8, 4};

struct Box {
  float lo[3] = {1e30f, 1e30f, 1e30f}, hi[3] = {-1e30f, -1e30f, -1e30f};
};

Box box_of(const Mesh& mesh) {
  Box box;
  for (size_t i = 0; i < mesh.positions.size(); ++i) {
    box.lo[i % 3] = std::min(box.lo[i % 3], mesh.positions[i]);
    box.hi[i % 3] = std::max(box.hi[i % 3], mesh.positions[i]);
  }
  return box;
}

// The whole model in view, from the front (+z), square.
Camera front_camera(const Box& box, float distance_in_radii) {
  Camera camera;
  float radius = 0;
  for (int k = 0; k < 3; ++k) {
    camera.target[k] = 0.5f * (box.lo[k] + box.hi[k]);
    radius += (box.hi[k] - box.lo[k]) * (box.hi[k] - box.lo[k]);
  }
  radius = 0.5f * std::sqrt(radius);
  std::copy_n(camera.target, 3, camera.eye);
  camera.eye[2] += distance_in_radii * radius;
  camera.width = camera.height = kPanelPixels;
  return camera;
}

// Every triangle with corners of its own, in a grey of its own (a hash of its index), so that the
// tessellation shows in a shaded picture.
Image faceted(const Mesh& mesh, const ViewParams& view) {
  std::vector<float> positions;
  std::vector<uint32_t> indices;
  std::vector<uint8_t> colors;
  positions.reserve(mesh.indices.size() * 3);
  colors.reserve(mesh.indices.size() * 4);
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    const uint8_t grey = uint8_t(150 + (uint32_t(f) * 2654435761u >> 26));  // 150 .. 213
    for (int c = 0; c < 3; ++c) {
      const uint32_t v = mesh.indices[3 * f + size_t(c)];
      positions.insert(positions.end(), &mesh.positions[3 * size_t(v)], &mesh.positions[3 * size_t(v)] + 3);
      colors.insert(colors.end(), {grey, grey, grey, 255});
      indices.push_back(uint32_t(indices.size()));
    }
  }
  return render(RenderMesh{positions, indices, colors}, view);
}

Mesh lod_at(const MultilevelMesh& mesh, MultilevelLod& lod, uint32_t level) {
  lod.set_level(level);
  return lod_mesh(mesh, lod);
}

// The level whose LOD has the triangle count nearest `triangles`.
uint32_t level_nearest(const std::vector<uint64_t>& lod_triangles, uint64_t triangles) {
  uint32_t best = 0;
  const auto distance = [&](uint32_t l) {
    const uint64_t t = lod_triangles[l];
    return t > triangles ? t - triangles : triangles - t;
  };
  for (uint32_t l = 1; l < lod_triangles.size(); ++l)
    if (distance(l) < distance(best)) best = l;
  return best;
}

std::string picture(const std::filesystem::path& dir, const std::string& file, const std::vector<Image>& panels,
                    const std::string& caption) {
  save_png((dir / file).string(), side_by_side(panels));
  return "![" + caption + "](" + file + ")\n\n" + caption + ".\n\n";
}

std::string figure_1(const std::filesystem::path& dir, const std::string& name, const MultilevelMesh& mesh,
                     const ViewParams& view) {
  MultilevelLod lod(mesh);
  std::vector<uint64_t> triangles(mesh.level_count());
  for (uint32_t l = 0; l < mesh.level_count(); ++l) {
    lod.set_level(l);
    triangles[l] = lod.indices().size() / 3;
  }
  std::vector<Image> panels;
  std::string counts;
  for (const uint64_t want : kPaperLodTriangles) {
    const uint32_t level = level_nearest(triangles, want);
    panels.push_back(faceted(lod_at(mesh, lod, level), view));
    counts += (counts.empty() ? "" : ", ") + std::to_string(triangles[level]) + " (level " + std::to_string(level) + ")";
  }
  return picture(dir, "multilevel-fig1-" + name + ".png", panels,
                 "Fig. 1, " + name + ": the LODs nearest the paper's 247, 665, 1,519 and 4,350 triangles: " + counts +
                     " triangles");
}

std::string figure_11(const std::filesystem::path& dir, const std::string& name, const Mesh& input,
                      const ViewParams& view) {
  const std::vector<VertexClustering> clusterings = grid_clusterings(input, kClusterGrids);
  const MultilevelMesh clustered = build_multilevel_from_clusterings(input, clusterings);
  MultilevelLod lod(clustered);
  std::vector<Image> panels;
  std::string counts;
  const uint32_t coarsest = clustered.level_count() - 1;
  for (uint32_t level = coarsest >= 3 ? coarsest - 2 : 0; level <= coarsest; ++level) {
    const Mesh m = lod_at(clustered, lod, level);
    counts += (counts.empty() ? "" : ", ") + std::to_string(m.face_count());
    panels.push_back(faceted(m, view));
  }
  if (coarsest > 0) {
    lod.geomorph(coarsest - 1, 0.5f);
    panels.push_back(faceted(lod_mesh(clustered, lod), view));
  }
  return picture(dir, "multilevel-fig11-" + name + ".png", panels,
                 "Fig. 11, " + name + ": the LODs of grid clusterings (16³, 8³ and 4³ cells; " + counts +
                     " triangles, non-manifold where cells merge sheets) and the geomorph halfway between the two "
                     "coarsest");
}

std::string figure_15(const std::filesystem::path& dir, const std::string& name, const MultilevelMesh& mesh,
                      const ViewParams& whole, const Box& box) {
  const MultilevelDag dag = build_multilevel_dag(mesh);
  // A close camera on the front's upper left: what it sees is refined, the rest stays coarse.
  Camera close = front_camera(box, 0.9f);
  const float shift[2] = {-0.25f * (box.hi[0] - box.lo[0]), 0.25f * (box.hi[1] - box.lo[1])};
  for (int k = 0; k < 2; ++k) {
    close.eye[k] += shift[k];
    close.target[k] += shift[k];
  }
  const ViewParams close_view = make_view(close, box.lo, box.hi);
  MultilevelRefinement refinement(dag);
  refinement.refine_to(splits_for_view(mesh, dag, close_view, 1.0f));
  MultilevelLod lod(mesh);
  const std::vector<Image> panels = {faceted(lod_at(mesh, lod, 0), whole),
                                     faceted(lod_at(mesh, lod, mesh.level_count() - 1), whole),
                                     faceted(local_mesh(mesh, dag, refinement).mesh, whole)};
  return picture(dir, "multilevel-fig15-" + name + ".png", panels,
                 "Fig. 15, " + name + ": the full mesh, the coarsest LOD, and the coarsest refined through the DAG "
                 "for a close view of its upper left (the splits whose star covers more than 1 pixel there)");
}

}  // namespace

std::string multilevel_figures(const std::filesystem::path& dir, const std::string& name, const MultilevelMesh& mesh) {
  MultilevelLod finest(mesh);
  const Mesh input = lod_at(mesh, finest, 0);
  const Box box = box_of(input);
  const ViewParams view = make_view(front_camera(box, 2.4f), box.lo, box.hi);
  std::fprintf(stderr, "bench: E10 %s: gueziec et al.'s figures ...\n", name.c_str());
  return "### gueziec et al.'s pictures (" + name + ")\n\n" + figure_1(dir, name, mesh, view) +
         figure_11(dir, name, input, view) + figure_15(dir, name, mesh, view, box);
}

}  // namespace pms::bench
