// Hoppe 1996 progressive meshes with Garland & Heckbert 1997 quadrics: always collapse the
// cheapest valid half-edge next. This is the classic view-independent PM order; its hierarchy is
// as deep as the survivor chains get, which is what the balanced order avoids.
#include <algorithm>
#include <queue>

#include "builder/simplify.h"

namespace pms {
namespace {

struct QueueEntry {
  double cost;
  uint32_t t, u, version;
  bool operator>(const QueueEntry& o) const { return cost > o.cost || (cost == o.cost && t > o.t); }
};

class GreedySimplifier {
 public:
  explicit GreedySimplifier(CollapseMesh& mesh) : mesh_(mesh), version_(mesh.vertex_count(), 0) {}

  // Queues t's cheapest target that is valid now.
  void refresh(uint32_t t) {
    ++version_[t];
    mesh_.neighbours(t, neighbours_);
    targets_.clear();
    for (uint32_t u : neighbours_)
      targets_.push_back({mesh_.quadric(t).error_sum(mesh_.quadric(u), mesh_.position(u)), t, u, version_[t]});
    std::sort(targets_.begin(), targets_.end(),
              [](const QueueEntry& a, const QueueEntry& b) { return a.cost < b.cost; });
    CollapseSite site;
    for (const QueueEntry& e : targets_)
      if (mesh_.check_collapse(t, e.u, site)) {
        queue_.push(e);
        return;
      }
  }

  bool pop(QueueEntry& out) {
    while (!queue_.empty()) {
      out = queue_.top();
      queue_.pop();
      if (mesh_.alive(out.t) && mesh_.alive(out.u) && version_[out.t] == out.version) return true;
    }
    return false;
  }

  const std::vector<uint32_t>& neighbours_of(uint32_t v) {
    mesh_.neighbours(v, ring_);
    return ring_;
  }

 private:
  CollapseMesh& mesh_;
  std::vector<uint32_t> version_;
  std::vector<uint32_t> neighbours_, ring_;
  std::vector<QueueEntry> targets_;
  std::priority_queue<QueueEntry, std::vector<QueueEntry>, std::greater<>> queue_;
};

}  // namespace

CollapseForest simplify_greedy(const Mesh& input, const BuildOptions& options) {
  CollapseMesh mesh(input);
  CollapseRecorder recorder(input, mesh, options.deviation);
  GreedySimplifier simplifier(mesh);
  const uint32_t start = mesh.alive_vertex_count();
  const uint32_t target = uint32_t(std::clamp<uint64_t>(options.base_vertices, 1, start));  // 0 -> 1: no limit
  for (uint32_t v = 0; v < mesh.vertex_count(); ++v) simplifier.refresh(v);
  QueueEntry e;
  CollapseSite site;
  std::vector<uint32_t> ring;
  while (mesh.alive_vertex_count() > target && simplifier.pop(e)) {
    if (!mesh.check_collapse(e.t, e.u, site)) {
      simplifier.refresh(e.t);  // the neighbourhood changed since it was queued
      continue;
    }
    recorder.apply(e.t, e.u, site);
    recorder.flush();  // the next collapse may involve u again
    ring = simplifier.neighbours_of(e.u);
    simplifier.refresh(e.u);
    for (uint32_t w : ring) simplifier.refresh(w);
    if ((recorder.collapses() & 4095) == 0)
      report(options.progress, "simplify", double(start - mesh.alive_vertex_count()) / double(start - target));
  }
  return recorder.finish();
}

}  // namespace pms
