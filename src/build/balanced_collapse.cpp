// Kim, Lee, Kobbelt 2005 §6.2 (balanced vertex hierarchy); Xia & Varshney 1996 (independent sets of
// collapses); Garland & Heckbert 1997 (quadric error). Each round takes the cheapest valid
// half-edge collapses such that no vertex takes part in two of them, so a round raises any
// subtree by at most one level; the cost is weighted by the height the new node would have, so
// short subtrees merge first and node ids stay short.
#include <algorithm>
#include <cmath>

#include "build/bounds.h"
#include "build/simplify.h"

namespace pms {
namespace {

// Targets kept per vertex: the best one may be blocked this round while the next is fine.
constexpr int kTargetsPerVertex = 3;
// Share of the live vertices one round may remove: a lower share keeps the order closer to the
// greedy quadric order (better intermediate meshes), a higher one gives fewer levels.
constexpr double kRoundShare = 0.25;
// Height weighting: key = (cost + epsilon) * 4^height. Exponential, because quadric
// costs span orders of magnitude and a polynomial weight barely reorders them.
constexpr int kHeightBaseLog2 = 2;  // base 4
// A round removing fewer than this share of the live vertices ends the simplification: past that
// point (components stuck at a few vertices) every further round would add a level to the
// hierarchy, i.e. one more bit to every node id, for a handful of vertices.
constexpr double kMinRoundShare = 0.02;

struct Entry {
  double key;
  uint32_t t, u;
};

// Ties broken by vertex so the order, hence the hierarchy, is the same on every run.
bool by_key(const Entry& a, const Entry& b) {
  return a.key < b.key || (a.key == b.key && (a.t < b.t || (a.t == b.t && a.u < b.u)));
}

void collect_candidates(CollapseMesh& mesh, const CollapseRecorder& recorder, double epsilon,
                        std::vector<uint32_t>& neighbours, std::vector<Entry>& out) {
  out.clear();
  for (uint32_t t = 0; t < mesh.vertex_count(); ++t) {
    if (!mesh.alive(t)) continue;
    mesh.neighbours(t, neighbours);
    Entry best[kTargetsPerVertex];
    int kept = 0;
    const uint32_t height_t = recorder.height(t);
    for (uint32_t u : neighbours) {
      const double cost = mesh.quadric(t).error_sum(mesh.quadric(u), mesh.position(u));
      const int height = int(std::max(height_t, recorder.height(u)));
      const Entry e{std::ldexp(cost + epsilon, kHeightBaseLog2 * height), t, u};
      int i;
      if (kept < kTargetsPerVertex) {
        i = kept++;
      } else if (e.key < best[kTargetsPerVertex - 1].key) {
        i = kTargetsPerVertex - 1;
      } else {
        continue;
      }
      best[i] = e;
      for (; i > 0 && best[i].key < best[i - 1].key; --i) std::swap(best[i], best[i - 1]);
    }
    out.insert(out.end(), best, best + kept);
  }
}

}  // namespace

CollapseForest simplify_balanced(const Mesh& input, const BuildOptions& options) {
  CollapseMesh mesh(input);
  CollapseRecorder recorder(input, mesh);
  const uint32_t start = mesh.alive_vertex_count();
  const uint32_t target = uint32_t(std::clamp<uint64_t>(options.base_vertices, 1, start));  // 0 -> 1: no limit
  const double diagonal = bounds_of(input.positions).diagonal();
  // Keeps zero-error collapses (flat regions) ordered by height too.
  const double epsilon = 1e-10 * diagonal * diagonal;

  std::vector<Entry> entries;
  std::vector<uint32_t> neighbours;
  std::vector<uint8_t> touched(mesh.vertex_count(), 0);
  CollapseSite site;
  while (mesh.alive_vertex_count() > target) {
    collect_candidates(mesh, recorder, epsilon, neighbours, entries);
    const uint32_t alive = mesh.alive_vertex_count();
    const uint32_t quota = std::min<uint32_t>(alive - target, std::max<uint32_t>(1, uint32_t(alive * kRoundShare)));
    std::fill(touched.begin(), touched.end(), 0);
    // Usually the quota fills from the cheapest few quota-sized chunks: sort only what is walked.
    uint32_t accepted = 0;
    size_t sorted_end = 0;
    for (size_t i = 0; i < entries.size() && accepted < quota; ++i) {
      if (i == sorted_end) {
        const size_t chunk_end = std::min(entries.size(), sorted_end + 2 * size_t(quota) + 1024);
        std::nth_element(entries.begin() + sorted_end, entries.begin() + chunk_end - 1, entries.end(), by_key);
        std::sort(entries.begin() + sorted_end, entries.begin() + chunk_end, by_key);
        sorted_end = chunk_end;
      }
      const Entry& e = entries[i];
      if (touched[e.t] || touched[e.u]) continue;
      if (!mesh.check_collapse(e.t, e.u, site)) continue;
      recorder.apply(e.t, e.u, site);
      touched[e.t] = touched[e.u] = 1;
      ++accepted;
    }
    if (accepted == 0 || accepted < kMinRoundShare * alive) break;
    report(options.progress, "simplify", double(start - mesh.alive_vertex_count()) / double(start - target));
  }
  return recorder.finish();
}

}  // namespace pms
