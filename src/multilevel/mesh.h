// Progressive multilevel meshes (gueziec, taubin, horn, lazarus 1999, "Progressive multilevel mesh"):
// vertices and triangles sorted by decreasing level plus a representative per vertex, so the LOD of any
// level is one pass over index arrays, and a fractional level is a geomorph between two of them.
#pragma once
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "io/mesh.h"
#include "multilevel/representative_array.h"

namespace pms {

// The secondary array of one LOD (gueziec et al.: going from a level to the next finer, "the positions and
// properties ... of the representatives ... may be changed by reading them from a secondary array"): the
// vertices of LOD l (below n_l) that stand elsewhere while LOD l is shown than at their own values, e.g. a
// clustering's surviving vertex at its cluster's position. Normals and colours travel when the mesh has
// them; texture coordinates never change (a cluster may span charts).
struct ChangedVertices {
  std::vector<uint32_t> vertex;   // strictly ascending
  std::vector<float> positions;   // dimension per entry
  std::vector<float> normals;     // 3 per entry when the mesh has normals
  std::vector<uint8_t> colors;    // 4 per entry when the mesh has colours

  size_t size() const { return vertex.size(); }
  bool empty() const { return vertex.empty(); }
};

// Levels run from 0 (finest) to level_count() - 1 (coarsest). LOD l is made of the vertices and triangles
// of levels >= l: a prefix of both arrays, [0, vertex_count[l]) and [0, triangle_count[l]). A triangle of
// LOD l that names a vertex >= vertex_count[l] follows representatives (each lower than the vertex it
// stands for) until it falls below vertex_count[l].
struct MultilevelMesh {
  static constexpr uint32_t kNoRepresentative = RepresentativeArray::kNone;

  uint32_t dimension = 3;                // coordinates per vertex (the paper's Fig. 6 is 2D)
  std::vector<float> positions;          // dimension per vertex
  std::vector<float> normals;            // 3 per vertex, or empty
  std::vector<uint8_t> colors;           // r g b a per vertex, or empty
  std::vector<float> texcoords;          // u v per vertex, or empty
  std::vector<uint32_t> triangles;       // 3 per triangle
  RepresentativeArray representative;    // per vertex; kNoRepresentative where none is stored
  std::vector<uint32_t> vertex_count;    // n_l per level: vertices of levels >= l (non-increasing in l)
  std::vector<uint32_t> triangle_count;  // likewise for triangles
  // Per level, the secondary array of its LOD (changed[0] is always empty: LOD 0 is the primary arrays);
  // empty when no LOD changes anything. A vertex's values in LOD l are its entry in changed[l], else its own.
  std::vector<ChangedVertices> changed;

  uint32_t level_count() const { return uint32_t(vertex_count.size()); }
  uint32_t vertices() const { return vertex_count.empty() ? 0 : vertex_count[0]; }
  uint32_t faces() const { return triangle_count.empty() ? 0 : triangle_count[0]; }
  uint64_t stored_representatives() const;
  uint64_t changed_vertices() const;  // entries of every level's secondary array
  bool changes(uint32_t level) const { return level < changed.size() && !changed[level].empty(); }
  // Vertex v's position in 3D (a 2D mesh lies in z = 0).
  void point(uint32_t v, float p[3]) const {
    p[2] = 0;
    for (uint32_t k = 0; k < dimension; ++k) p[k] = positions[size_t(v) * dimension + k];
  }
  // Vertices and triangles that belong to level l itself (its batch in a file).
  uint32_t level_vertices(uint32_t l) const;
  uint32_t level_triangles(uint32_t l) const;
};

// pms::Error ("WHERE: what") unless the structure is consistent: array sizes, non-increasing counts,
// indices in range, every representative below its vertex, and every triangle of level l resolving each
// corner below n_l. What the readers check after parsing, and the writers before writing.
void validate_multilevel(const std::string& where, const MultilevelMesh& mesh);

// The representatives a file states right after triangle t of level l (Fig. 6: "6, 2, 8, 0, 1"): for each
// corner at or above n_l whose representative was not stated before, that representative, and if it is
// itself at or above n_l and unstated, its own, and so on. Appends (vertex, representative) pairs to `out`;
// `stated` (one flag per vertex) remembers what earlier triangles stated.
void representatives_stated_by(const MultilevelMesh& mesh, uint32_t t, uint32_t n_l, std::vector<uint8_t>& stated,
                               std::vector<uint32_t>& out);

// The (vertex, representative) pairs level `level`'s batch carries: in the order its triangles state them,
// then those of its own vertices that no triangle states (only geomorphs use them), by vertex. Levels are
// taken coarsest first with one `stated` (a flag per vertex) across them.
std::vector<uint32_t> level_representatives(const MultilevelMesh& mesh, uint32_t level, std::vector<uint8_t>& stated);

// Per level, how many representatives its triangles state (what its ASCII batch carries).
std::vector<uint32_t> representatives_per_level(const MultilevelMesh& mesh);

// Per level, how many of its own vertices have a representative that no triangle states. No discrete LOD
// needs one (a triangle of level k states every representative LOD k needs, and a vertex of level l is
// below n_l, so only coarser triangles can state its); a geomorph from level l to l + 1 puts the vertex
// there at t = 0 (MultilevelRepresentatives::geomorph). The binary and compressed forms carry them with
// the vertex's level; the paper's ASCII form has no place for them and leaves them out.
std::vector<uint32_t> geomorph_representatives_per_level(const MultilevelMesh& mesh);
uint64_t geomorph_representative_count(const MultilevelMesh& mesh);  // their sum

// Per level, the geometric error of its LOD: the longest distance from a vertex of a finer level to the
// vertex it stands at in that LOD (its path-compressed representative); 0 for level 0. What a screen-size
// rule projects to pixels. O(n) per level.
std::vector<float> multilevel_level_errors(const MultilevelMesh& mesh);

// One LOD of a multilevel mesh at a time (the paper's setLevel). The mesh must outlive it.
class MultilevelLod {
 public:
  explicit MultilevelLod(const MultilevelMesh& mesh);

  // LOD `level` straight from whatever level was set: a path-compressed copy of the representatives
  // (the original array is kept) and one pass over the LOD's triangles.
  void set_level(uint32_t level);
  // setLevel(float): geomorph(floor(x), floor(x) + 1 - x); integral x is set_level(uint32_t).
  void set_level(float x);
  // LOD lo's connectivity with the vertices of level lo at (1 - t) * their representative's position at
  // level lo + 1 + t * their own (attributes likewise): t = 1 is LOD lo; t = 0 is LOD lo + 1 as a surface
  // (level lo's triangles have zero area) when every vertex of level lo that the LOD names has a
  // representative, which the geomorph representatives ensure; one without stays put.
  void geomorph(uint32_t lo, float t);
  // The same between LOD lo and any coarser LOD hi (gueziec et al. §"Vertex clustering": LOD hi is LOD lo
  // after the clusterings of levels lo .. hi - 1, and their composition is a clustering too): the vertices
  // of levels lo .. hi - 1 blend from where LOD hi puts them (t = 0) to their own positions (t = 1), so
  // one LOD switch across many levels is one geomorph. level() is hi - (hi - lo) * t.
  void geomorph(uint32_t lo, uint32_t hi, float t);

  float level() const { return level_; }
  uint32_t vertex_count() const { return vertex_count_; }
  std::span<const uint32_t> indices() const { return indices_; }
  std::span<const float> positions() const;
  std::span<const float> normals() const;
  std::span<const uint8_t> colors() const;
  std::span<const float> texcoords() const;

 private:
  void connect(uint32_t level);
  bool connect_by_walking(uint32_t level);
  void prepare_morph(uint32_t lo, uint32_t hi);

  const MultilevelMesh& mesh_;
  float level_ = -1;
  uint32_t connected_ = 0xFFFFFFFFu;  // the level whose connectivity indices_ holds
  uint32_t vertex_count_ = 0;
  std::vector<uint32_t> pc_rep_;  // path-compressed representatives for `connected_`
  std::vector<uint32_t> indices_;
  // The values of the vertices of one LOD: what positions() and the others show, and a geomorph's ends.
  struct Values {
    std::vector<float> positions, normals, texcoords;
    std::vector<uint8_t> colors;
  };
  // LOD `level`'s values of its vertices: the primary arrays with its secondary array applied.
  void values_at(uint32_t level, Values& out) const;
  // `from` and `to` blended at t into shown_, for vertices [begin, end).
  void blend(float t, uint32_t begin, uint32_t end);

  // The levels morph_source_ is for: per vertex of levels morph_lo_ .. morph_hi_ - 1, where LOD morph_hi_
  // puts it.
  uint32_t morph_lo_ = 0xFFFFFFFFu, morph_hi_ = 0xFFFFFFFFu;
  std::vector<uint32_t> morph_source_;
  // shown_ holds what positions() and the others return while own_values_ (a geomorph, or a LOD whose
  // secondary array changes something); a geomorph blends morph_from_ (LOD hi's values where each vertex
  // stands there) into morph_to_ (LOD lo's).
  bool own_values_ = false;
  Values shown_, morph_from_, morph_to_;
};

// The LOD `lod` holds as a plain indexed mesh (a 2D mesh lies in z = 0), with its normals, colours and
// texture coordinates.
Mesh lod_mesh(const MultilevelMesh& mesh, const MultilevelLod& lod);

}  // namespace pms
