#include <algorithm>

#include "builder/simplify.h"
#include "common/parallel.h"

namespace pms {
namespace {

uint32_t slot_of(const uint32_t* face, uint32_t v) { return face[0] == v ? 0 : face[1] == v ? 1 : 2; }

}  // namespace

CollapseRecorder::CollapseRecorder(const Mesh& mesh, CollapseMesh& collapse_mesh, Deviation deviation)
    : mesh_(collapse_mesh), refinement_(mesh, collapse_mesh, 2 * mesh.vertex_count(), deviation) {
  const uint32_t n = uint32_t(mesh.vertex_count());
  forest_.leaf_count = n;
  current_.resize(n);
  for (uint32_t v = 0; v < n; ++v) current_[v] = {v, 0, v};
  // At most n - 1 collapses: reserving spares the copies (and page faults) of repeated growth.
  for (auto* per_collapse : {&forest_.child_t, &forest_.child_u, &forest_.cut_l, &forest_.cut_r})
    per_collapse->reserve(n);
  forest_.survivor_leaf.reserve(2 * size_t(n));
  forest_.survivor_leaf.resize(n);
  for (uint32_t v = 0; v < n; ++v) forest_.survivor_leaf[v] = v;
}

void CollapseRecorder::apply(uint32_t t, uint32_t u, const CollapseSite& site) {
  // The fundamental cut vertex is the input corner of the removed face at the apex (dual view).
  auto cut_leaf = [&](uint32_t face, uint32_t apex) {
    if (face == UINT32_MAX) return UINT32_MAX;
    return mesh_.original_corner(3 * face + slot_of(mesh_.face(face), apex));
  };
  const CurrentNode before_t = current_[t], before_u = current_[u];
  const uint32_t s = forest_.node_count();
  forest_.child_t.push_back(before_t.node);
  forest_.child_u.push_back(before_u.node);
  forest_.cut_l.push_back(cut_leaf(site.face_l, site.l));
  forest_.cut_r.push_back(cut_leaf(site.face_r, site.r));
  forest_.survivor_leaf.push_back(before_u.survivor_leaf);
  mesh_.collapse(t, u, site);
  current_[u] = {s, std::max(before_t.height, before_u.height) + 1, before_u.survivor_leaf};
  refinement_.merge_leaves(s, before_t.node, before_u.node, t, u);
  pending_.push_back({s, before_t.node, before_u.node, u});
}

void CollapseRecorder::end_round() {
  if (pending_.empty()) return;  // nothing to wait for: the round computing may go on
  // Accepted in cost order, i.e. scattered over the mesh; captured and computed in vertex order, the
  // fans and samples they read are neighbours in memory. Every record of one round reads only the
  // previous rounds' info and the round's final mesh, so the order does not change the result.
  std::sort(pending_.begin(), pending_.end(), [](const auto& a, const auto& b) { return a.u < b.u; });
  // This round's children may be the last round's nodes. Waiting before capturing keeps one round's
  // copy alive at a time, at the price of the other core idling while this one captures.
  computing_.wait();
  computing_round_.capture(
      pending_, mesh_, [this](uint32_t v) { return refinement_.samples_of(v); },
      [this](uint32_t v) { return current_[v].survivor_leaf; });
  const auto compute = [this](size_t begin, size_t end) {
    computing_round_.for_each(
        begin, end,
        [this](const CapturedRound::Collapse& c, std::span<const uint32_t> corners, std::span<const uint32_t> samples) {
          refinement_.compute(c.s, c.t_node, c.u_node, corners, samples);
        });
  };
  // Starting a thread costs more than computing a few hundred records.
  const size_t count = computing_round_.collapses.size();
  if (count < 2 * CapturedRound::kChunk) compute(0, count);
  else computing_.start(count, CapturedRound::kChunk, compute);
}

void CollapseRecorder::flush() {
  end_round();
  computing_.wait();
}

void CollapseRecorder::compact(std::vector<uint32_t>& new_index) {
  end_round();
  mesh_.compact(new_index);
  uint32_t live = 0;
  for (uint32_t v = 0; v < new_index.size(); ++v)
    if (new_index[v] != UINT32_MAX) current_[live++] = current_[v];
  current_.resize(live);
  refinement_.compact(new_index);
}

CollapseForest CollapseRecorder::finish() {
  flush();
  std::vector<uint32_t> root_index(mesh_.vertex_count(), UINT32_MAX);
  for (uint32_t v = 0; v < mesh_.vertex_count(); ++v) {
    if (!mesh_.alive(v)) continue;
    root_index[v] = uint32_t(forest_.root_node.size());
    forest_.root_node.push_back(current_[v].node);
  }
  for (uint32_t f = 0; f < mesh_.face_count(); ++f) {
    if (!mesh_.face_alive(f)) continue;
    for (int k = 0; k < 3; ++k) forest_.base_faces.push_back(root_index[mesh_.face(f)[k]]);
  }
  forest_.info = refinement_.take();
  forest_.info.resize(forest_.node_count());
  return std::move(forest_);
}

}  // namespace pms
