// The mesh as a renderer's buffers (docs/architecture.md, "Viewer"): flat arrays a GPU takes as they are,
// kept up to date in place, with the ranges that changed since the last update so that a renderer uploads
// only those (glBufferSubData, WebGL's bufferSubData).
//
// Slots, not compaction: vertex i is the hierarchy's slot i and triangle t the mesh's face slot t, both
// stable while the mesh refines and coarsens, so a split or a collapse touches only its own few entries. A
// freed face slot holds the degenerate triangle (0, 0, 0) until the mesh reuses it (its free list); an
// inactive vertex slot keeps its last values and no triangle refers to it. The cost is memory: every slot
// the hierarchy ever held, and every face slot at the mesh's largest, against an extracted mesh's active
// vertices and live faces; the gain is that nothing moves when the front does. The multilevel mode's
// levels number their own vertices and triangles: a level switch changes what it changes.
// Shared with the browser build: single-threaded.
#pragma once
#include <cstdint>
#include <vector>

#include "io/mesh.h"
#include "spm/adapt.h"

namespace pms::client {

struct BufferRange {
  uint32_t first = 0, count = 0;  // in elements: vertices, or triangles
  friend bool operator==(const BufferRange&, const BufferRange&) = default;
};

struct MeshBuffers {
  std::vector<float> positions;   // 3 per vertex, where it is shown (geomorphs included)
  std::vector<float> normals;     // 3 per vertex: the model's, or computed from the faces around it
  std::vector<uint8_t> colors;    // 4 per vertex: the model's, or opaque white
  std::vector<uint32_t> indices;  // 3 per triangle, CCW; (0, 0, 0) for a free slot
  // What changed since the update before, in increasing order, runs closer than kMergeGap merged (one
  // upload of a few unchanged entries costs less than another call). Arrays that grew count as changed
  // from their old end: a renderer reallocates such a buffer.
  std::vector<BufferRange> changed_vertices, changed_triangles;
  uint64_t updates = 0;
  // What the last update from a refinement read: the mesh's changes(), the hierarchy's size and the face
  // slots, with no geomorph moving. The same again means nothing can have changed (a vertex moves only by
  // a geomorph, which a split or a collapse starts), and the update is skipped.
  struct Source {
    uint64_t changes = 0;
    size_t slots = 0, faces = 0;
    bool at_rest = false;
    friend bool operator==(const Source&, const Source&) = default;
  } source;
  // Working space of update_buffers, kept so that an update allocates nothing once the mesh has grown.
  std::vector<float> computed_normals;
  std::vector<uint64_t> changed_blocks;

  static constexpr uint32_t kMergeGap = 64;
  uint32_t vertex_count() const { return uint32_t(positions.size() / 3); }
  uint32_t triangle_count() const { return uint32_t(indices.size() / 3); }
};

// Brings `buffers` to the refinement's mesh: vertex i = hierarchy slot i, triangle t = face slot t. Reads
// every face slot and active vertex once (no allocation once the arrays have grown), never the inactive
// slots; computes normals from the faces when the hierarchy has none.
void update_buffers(const SelectiveRefinement& refinement, MeshBuffers& buffers);
// Brings `buffers` to `mesh` as it numbers its vertices and triangles (the multilevel mode's LOD).
void update_buffers(const Mesh& mesh, MeshBuffers& buffers);

}  // namespace pms::client
