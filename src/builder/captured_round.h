// One balanced round's collapses, with what computing their refinement info reads of the working mesh
// (the faces around each survivor, their corners as the leaves whose positions they have) and of the
// leaf samples, copied when the round ends: the next round changes both while this round's bounds are
// computed on another core (CollapseRecorder::end_round). The copy is alive beside the next round's
// collapsing, so it is small (16 bytes and two counts per collapse, 12 bytes per face, 4 per sample) and
// reuses its arrays: the first round is the largest, and arrays freed and allocated anew each round
// left the builder's heap (never trimmed: docs/internals.md, "Builder") fragmented, its peak higher.
#pragma once
#include <algorithm>
#include <cassert>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "builder/collapse_mesh.h"
#include "builder/leaf_samples.h"
#include "common/parallel.h"

namespace pms {

struct CapturedRound {
  static constexpr uint32_t kMaxFanFaces = 32;  // faces of a fan measured against (more only widen a bound)
  static constexpr size_t kChunk = 256;         // collapses per stored offset; work is handed out in these
  static_assert(kMaxFanFaces <= 255 && LeafSamples::kMax <= 255, "counts are kept in bytes");
  static constexpr size_t kParallelChunks = 8;  // fewer are captured on the calling thread alone

  struct Collapse {
    uint32_t s, t_node, u_node;  // node s was made from t_node and u_node
    uint32_t u;                  // the working mesh's vertex that carried s when the round ended
  };
  std::vector<Collapse> collapses;
  std::vector<uint8_t> face_count, sample_count;
  std::vector<uint32_t> corners;  // 3 leaves per face, in face order
  std::vector<uint32_t> samples;
  // Where each kChunk collapses' corners and samples begin; one more entry holds where the last ends.
  std::vector<size_t> chunk_corners, chunk_samples;

  // The round of `round_collapses`, which gets back the previous round's list (cleared, for its room).
  // samples_of(v): the leaf samples vertex v carries; leaf_of(v): the leaf whose position vertex v has.
  // Counted, then copied, a range of chunks per core: the computing core waits for this.
  template <class SamplesOf, class LeafOf>
  void capture(std::vector<Collapse>& round_collapses, const CollapseMesh& mesh, const SamplesOf& samples_of,
               const LeafOf& leaf_of) {
    collapses.swap(round_collapses);
    round_collapses.clear();
    const size_t n = collapses.size(), chunks = (n + kChunk - 1) / kChunk;
    face_count.resize(n);
    sample_count.resize(n);
    chunk_corners.resize(chunks + 1);
    chunk_samples.resize(chunks + 1);
    for_each_range(chunks, kParallelChunks, [&](size_t first, size_t last) {
      for (size_t chunk = first; chunk < last; ++chunk) {
        size_t corner_total = 0, sample_total = 0;
        for (size_t i = chunk * kChunk; i < std::min(n, (chunk + 1) * kChunk); ++i) {
          uint32_t faces = 0;
          mesh.for_each_live_face(collapses[i].u, [&](uint32_t, uint32_t) { faces += faces < kMaxFanFaces; });
          face_count[i] = uint8_t(faces);
          sample_count[i] = uint8_t(samples_of(collapses[i].u).size());
          corner_total += 3 * size_t(faces);
          sample_total += sample_count[i];
        }
        chunk_corners[chunk + 1] = corner_total, chunk_samples[chunk + 1] = sample_total;
      }
    });
    chunk_corners[0] = chunk_samples[0] = 0;
    for (size_t chunk = 0; chunk < chunks; ++chunk) {
      chunk_corners[chunk + 1] += chunk_corners[chunk];
      chunk_samples[chunk + 1] += chunk_samples[chunk];
    }
    corners.resize(chunk_corners[chunks]);
    samples.resize(chunk_samples[chunks]);
    for_each_range(chunks, kParallelChunks, [&](size_t first, size_t last) {
      uint32_t* corner = corners.data() + chunk_corners[first];
      uint32_t* sample = samples.data() + chunk_samples[first];
      for (size_t i = first * kChunk; i < std::min(n, last * kChunk); ++i) {
        uint32_t faces = face_count[i];
        mesh.for_each_live_face(collapses[i].u, [&](uint32_t f, uint32_t) {
          if (faces == 0) return;
          --faces;
          for (int k = 0; k < 3; ++k) *corner++ = leaf_of(mesh.face(f)[k]);
        });
        for (const uint32_t leaf : samples_of(collapses[i].u)) *sample++ = leaf;
      }
    });
  }

  // fn(collapse, its fan's corners, its samples) for the collapses in [begin, end); begin a multiple of kChunk.
  template <class Fn>
  void for_each(size_t begin, size_t end, Fn&& fn) const {
    assert(begin % kChunk == 0);
    size_t corner = chunk_corners[begin / kChunk];
    size_t sample = chunk_samples[begin / kChunk];
    for (size_t i = begin; i < end; ++i) {
      const size_t corner_count = 3 * size_t(face_count[i]);
      fn(collapses[i], std::span(corners).subspan(corner, corner_count),
         std::span(samples).subspan(sample, sample_count[i]));
      corner += corner_count;
      sample += sample_count[i];
    }
  }
};

}  // namespace pms
