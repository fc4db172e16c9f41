// Builds the view-dependent progressive mesh of a cleaned input (kim-lee-kobbelt §6.2; Hoppe 1997;
// Garland & Heckbert 1997): QEM half-edge collapses in balanced rounds (or one at a time with
// `greedy`), the packed hierarchy, fundamental cut vertices and refinement info.
#pragma once
#include <cstdint>
#include <string>

#include "common/progress.h"
#include "io/mesh.h"
#include "spm/hierarchy.h"
#include "spm/pms_file.h"

namespace pms {

// What a node's deviation space (mu, delta) holds (docs/internals.md, "Refinement info").
enum class Deviation {
  estimate,  // Hoppe 1997's estimate: sampled leaves and the moved surface, at least each child's space.
  bound,     // a bound on the whole input surface below the node: sampled leaves, and each child's space
             // plus how far this collapse moved the surface (triangle inequality; the move is sampled).
             // The chain sums a move per level: ~1.4x the splits for the same τ (a close view of bunny).
};

struct BuildOptions {
  bool greedy = false;  // classic one-at-a-time PM order (the view-independent baseline)
  // Stop once the base mesh has this many vertices, or earlier when no valid collapse is left
  // (0: as coarse as the mesh allows). The default keeps the base a few KB and ids short: the last
  // few rounds below it add a level to the hierarchy each while removing only a handful of vertices.
  uint64_t base_vertices = 64;
  Deviation deviation = Deviation::estimate;
  // Each node's refinement info rounded up onto the lattice below its parent's (builder/nested_refine_info.h),
  // what split records code in a few bits; false keeps every node's own bounds (measurements).
  bool nested_info = true;
  ProgressFn progress;
};

struct BuildResult {
  Hierarchy hierarchy;
  BuildStats stats;
};

// The options as META records them (BuildStats::options), e.g. "balanced base_vertices=64 deviation=estimate".
std::string options_text(const BuildOptions& options);

// `mesh` must be an oriented 2-manifold (boundaries allowed), i.e. the output of clean_mesh().
// Throws pms::Error if it is not.
BuildResult build_progressive_mesh(const Mesh& mesh, const BuildOptions& options = {});

}  // namespace pms
