// Building a progressive multilevel mesh from vertex clusterings (gueziec et al. 1999, "From vertex
// clusterings", Fig. 12): topology may change and the mesh may be non-manifold; triangles that degenerate
// go to the level where they vanish; each cluster keeps its "preferred" ancestor, the one closest to it.
#pragma once
#include <cstdint>
#include <span>
#include <vector>

#include "io/mesh.h"
#include "multilevel/build.h"

namespace pms {

// One clustering of the current mesh: cluster[v] for every input vertex v (entries of vertices an earlier
// clustering removed are not read), and 3 floats per cluster, the position it stands at, which picks the
// preferred ancestor (the nearest; ties to the lower index). The ancestor keeps its own position in the
// primary array; the secondary array of the clustering's LOD moves it to the cluster's position, with the
// mean normal and colour of the input vertices it stands for.
struct VertexClustering {
  std::vector<uint32_t> cluster;
  std::vector<float> positions;
};

// Levels as the paper assigns them: clustering i removes every ancestor but the preferred one of each
// cluster (level i, its parent the preferred one) and the triangles it degenerates (level i); what is left
// takes the level after the last clustering. pms::Error for a map of the wrong size or a cluster without a
// position.
CollapseLevels assign_cluster_levels(const Mesh& mesh, std::span<const VertexClustering> clusterings);

// Clusterings by regular grids over the mesh's bounding box, N × N × N cells for each N in `resolutions`
// (`--cluster grid:N,...`, finest first); a cell's position is the mean of the input vertices in it.
std::vector<VertexClustering> grid_clusterings(const Mesh& mesh, std::span<const uint32_t> resolutions);

// assign_cluster_levels, merged to `level_count` (0: every level), then assembled with the representatives
// that triangles need and no others (Fig. 12-13: three suffice where the clusterings name six), and each
// coarse LOD's secondary array: the clustering that LOD ends with puts its vertices at their clusters.
MultilevelMesh build_multilevel_from_clusterings(const Mesh& mesh, std::span<const VertexClustering> clusterings,
                                                 uint32_t level_count = 0);

}  // namespace pms
