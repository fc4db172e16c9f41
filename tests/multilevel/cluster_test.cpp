// Progressive multilevel meshes from vertex clusterings (gueziec et al. 1999, Fig. 12-13): the paper's own
// example needs its three representatives and no more, gives Fig. 6's file, and grid clusterings of real
// meshes (non-manifold, topology changing) give LODs equal to the clusterings applied.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>

#include "common/error.h"
#include "fixtures/view_models.h"
#include "io/shapes.h"
#include "multilevel/cluster.h"
#include "multilevel/file.h"

namespace pms {
namespace {

constexpr uint32_t kNo = MultilevelMesh::kNoRepresentative;

// Fig. 12's finest mesh, numbered as Fig. 6 numbers it (vertex 6 at (-2.3, 2.3): Fig. 6 prints it as
// (2.3, 2.3), on top of vertex 8).
Mesh figure12_mesh() {
  Mesh m;
  const float xy[10][2] = {{-3, 3},    {3, 3},        {-3, -3},  {3, -3},      {-2.3f, 3},
                           {-3, 2.3f}, {-2.3f, 2.3f}, {2.3f, 3}, {2.3f, 2.3f}, {3, 2.3f}};
  for (const auto& p : xy) m.positions.insert(m.positions.end(), {p[0], p[1], 0});
  m.indices = {6, 2, 8, 3, 8, 2, 4, 6, 7, 5, 2, 6, 6, 4, 5, 4, 0, 5, 8, 3, 9, 9, 1, 8, 7, 8, 1, 8, 7, 6};
  return m;
}

// Every vertex its own cluster except `group`, which goes to one cluster at `at`.
VertexClustering one_group(const Mesh& mesh, std::initializer_list<uint32_t> group, std::array<float, 3> at) {
  VertexClustering c;
  c.cluster.resize(mesh.vertex_count());
  for (uint32_t v = 0; v < mesh.vertex_count(); ++v) {
    c.cluster[v] = v;
    c.positions.insert(c.positions.end(), &mesh.positions[3 * size_t(v)], &mesh.positions[3 * size_t(v)] + 3);
  }
  const uint32_t id = uint32_t(mesh.vertex_count());
  for (uint32_t v : group) c.cluster[v] = id;
  c.positions.insert(c.positions.end(), at.begin(), at.end());
  return c;
}

std::vector<std::array<uint32_t, 3>> lod_triangles(const MultilevelMesh& m, uint32_t level) {
  MultilevelLod lod(m);
  lod.set_level(level);
  std::vector<std::array<uint32_t, 3>> out;
  for (size_t i = 0; i < lod.indices().size(); i += 3)
    out.push_back({lod.indices()[i], lod.indices()[i + 1], lod.indices()[i + 2]});
  return out;
}

TEST(MultilevelCluster, Figure12NeedsOnlyThreeRepresentativesAndGivesFigure6) {
  const Mesh mesh = figure12_mesh();
  const std::vector<VertexClustering> clusterings = {one_group(mesh, {1, 7, 8, 9}, {3, 3, 0}),
                                                     one_group(mesh, {0, 4, 5, 6}, {-3, 3, 0})};
  const MultilevelMesh m = build_multilevel_from_clusterings(mesh, clusterings);
  validate_multilevel("fig12", m);
  EXPECT_EQ(m.vertex_count, (std::vector<uint32_t>{10, 7, 4}));
  EXPECT_EQ(m.triangle_count, (std::vector<uint32_t>{10, 6, 2}));
  EXPECT_EQ(m.stored_representatives(), 3u) << "the clusterings name 6 non-preferred ancestors; 3 suffice";
  EXPECT_EQ(m.representative, (std::vector<uint32_t>{kNo, kNo, kNo, kNo, kNo, kNo, 0, 1, 1, kNo}));
  EXPECT_EQ(m.triangles, mesh.indices) << "Fig. 6 lists the triangles in this order";
  // Each of the three is necessary: without it the structure is invalid.
  for (uint32_t v : {6u, 7u, 8u}) {
    MultilevelMesh fewer = m;
    fewer.representative[v] = kNo;
    EXPECT_THROW(validate_multilevel("fewer", fewer), Error) << "representative of " << v;
  }
  // Fig. 6's file describes the same mesh (up to its misprinted vertex 6).
  const std::string text = format_multilevel_ascii(m);
  const MultilevelMesh read = parse_multilevel_ascii("fig12.txt", text);
  EXPECT_EQ(read.triangles, m.triangles);
  EXPECT_EQ(read.representative, m.representative);
  for (uint32_t l = 0; l < 3; ++l)
    for (const auto& t : lod_triangles(m, l))
      EXPECT_TRUE(t[0] != t[1] && t[1] != t[2] && t[2] != t[0]) << "level " << l << ": degenerate triangles left";
}

// The reference: the input with the clusterings below level l applied (every removed vertex replaced by
// its preferred ancestor, chains followed), degenerate triangles dropped; as corner positions.
std::vector<std::array<float, 9>> applied(const Mesh& mesh, const CollapseLevels& levels, uint32_t l) {
  std::vector<std::array<float, 9>> out;
  for (size_t t = 0; t < mesh.face_count(); ++t) {
    uint32_t c[3];
    for (int k = 0; k < 3; ++k) {
      c[k] = mesh.indices[3 * t + k];
      while (levels.parent[c[k]] != kNo && levels.vertex_level[c[k]] < l) c[k] = levels.parent[c[k]];
    }
    if (c[0] == c[1] || c[1] == c[2] || c[2] == c[0]) continue;
    std::array<float, 9> f;
    for (int k = 0; k < 3; ++k) std::copy_n(&mesh.positions[3 * size_t(c[k])], 3, &f[3 * k]);
    out.push_back(f);
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<std::array<float, 9>> lod_faces(const MultilevelMesh& m, uint32_t l) {
  std::vector<std::array<float, 9>> out;
  for (const auto& t : lod_triangles(m, l)) {
    std::array<float, 9> f;
    for (int k = 0; k < 3; ++k) std::copy_n(&m.positions[3 * size_t(t[k])], 3, &f[3 * k]);
    out.push_back(f);
  }
  std::sort(out.begin(), out.end());
  return out;
}

void expect_grid_levels_are_the_clusterings(const Mesh& mesh, std::vector<uint32_t> grids) {
  const std::vector<VertexClustering> clusterings = grid_clusterings(mesh, grids);
  const CollapseLevels levels = assign_cluster_levels(mesh, clusterings);
  const MultilevelMesh m = assemble_multilevel(mesh, levels, MultilevelRepresentatives::discrete);
  validate_multilevel("grid", m);
  ASSERT_EQ(m.level_count(), grids.size() + 1);
  for (uint32_t l = 0; l < m.level_count(); ++l) EXPECT_EQ(lod_faces(m, l), applied(mesh, levels, l)) << "level " << l;
  EXPECT_LT(m.triangle_count.back(), m.faces() / 10);
  // Round trips stay exact for a non-manifold multilevel mesh too.
  const MultilevelMesh again = parse_multilevel_binary("grid.pml", format_multilevel_binary(m));
  EXPECT_EQ(again.triangles, m.triangles);
  EXPECT_EQ(again.representative, m.representative);
}

TEST(MultilevelCluster, GridLevelsAreTheClusteringsAppliedTorus) {
  expect_grid_levels_are_the_clusterings(make_torus(48, 24, 2.0f, 0.5f), {16, 6, 2});
}

TEST(MultilevelCluster, GridLevelsAreTheClusteringsAppliedBunny) {
  const test::BuiltModel* bunny = test::built_bunny();
  if (!bunny) GTEST_SKIP() << "../shared/models/bunny.ply.xz not found: this test needs the shared test meshes";
  expect_grid_levels_are_the_clusterings(bunny->input, {64, 16, 4});
}

TEST(MultilevelCluster, BadClusteringsAreRefused) {
  const Mesh mesh = figure12_mesh();
  VertexClustering short_map;
  short_map.cluster = {0, 1};
  short_map.positions = {0, 0, 0, 1, 1, 1};
  EXPECT_THROW(assign_cluster_levels(mesh, std::vector<VertexClustering>{short_map}), Error);
  VertexClustering no_position = one_group(mesh, {0, 1}, {0, 0, 0});
  no_position.cluster[3] = 99;
  EXPECT_THROW(assign_cluster_levels(mesh, std::vector<VertexClustering>{no_position}), Error);
  EXPECT_THROW(grid_clusterings(mesh, std::vector<uint32_t>{0}), Error);
}

}  // namespace
}  // namespace pms
