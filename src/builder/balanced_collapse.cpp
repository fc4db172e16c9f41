// Kim, Lee, Kobbelt 2005 §6.2 (balanced vertex hierarchy); Xia & Varshney 1996 (independent sets of
// collapses); Garland & Heckbert 1997 (quadric error). Each round takes the cheapest valid
// half-edge collapses such that no vertex takes part in two of them, so a round raises any
// subtree by at most one level and node ids stay short. The last rounds above the base are
// smaller and weight the cost by the height the new node would have (see RoundRule).
#include <algorithm>
#include <array>
#include <cmath>
#include <thread>

#include "builder/bounds.h"
#include "builder/simplify.h"

namespace pms {
namespace {

// Targets kept per vertex: the best one may be blocked this round while the next is fine.
constexpr int kTargetsPerVertex = 3;
constexpr uint32_t kTabulatedHeights = 64;  // far above any real hierarchy: ids must fit 64 bits

// How one round chooses: the share of the live vertices it may remove (a lower share keeps the order
// closer to the greedy quadric order, a higher one gives fewer levels and fewer rounds) and the height
// weighting, key = (cost + epsilon) * height_base^height (exponential, because quadric costs span orders
// of magnitude and a polynomial weight barely reorders them; base 1: the quadric cost alone).
struct RoundRule {
  double share;
  double height_base;
};
// While many vertices are live, the independent sets alone keep the trees shallow (a round raises a
// subtree by at most one level) and a height weight only trades quality for depth.
constexpr RoundRule kEarlyRounds{0.25, 1.0};
// The last rounds above the base build the nodes far views use: smaller rounds keep their order near the
// greedy one, and a mild height weight stops the survivors of the few big components from chaining a
// level per round. docs/internals.md ("Builder") says why.
constexpr RoundRule kLateRounds{0.10, 1.5};
// The late rounds start below this many times the base size (2,048 live vertices for the default 64).
constexpr uint32_t kLateRoundsBelowBase = 32;
// A round removing fewer than this share of its quota ends the simplification: past that point
// (components stuck at a few vertices) every further round would add a level to the hierarchy for
// a handful of vertices.
constexpr double kMinQuotaShare = 0.40;
constexpr size_t kPrefetchDistance = 8;

// height_base^height, tabulated: no libm call per edge.
class HeightWeights {
 public:
  explicit HeightWeights(double base) : base_(base) {
    for (uint32_t h = 0; h < kTabulatedHeights; ++h) table_[h] = std::pow(base, double(h));
  }
  double operator()(uint32_t height) const {
    return height < kTabulatedHeights ? table_[height] : std::pow(base_, double(height));
  }

 private:
  double base_;
  std::array<double, kTabulatedHeights> table_;
};

struct Entry {
  double key;
  uint32_t t, u;
};

// Ties broken by vertex so the order, hence the hierarchy, is the same on every run.
bool by_key(const Entry& a, const Entry& b) {
  return a.key < b.key || (a.key == b.key && (a.t < b.t || (a.t == b.t && a.u < b.u)));
}

// Best targets of the vertices in [begin, end) into `out`, which has room for kTargetsPerVertex each;
// returns how many. Read-only on the mesh, so chunks run in parallel.
size_t collect_range(const CollapseMesh& mesh, const CollapseRecorder& recorder, const HeightWeights& weight,
                     double epsilon, uint32_t begin, uint32_t end, NeighbourScratch& marks, Entry* out) {
  Entry* const first = out;
  std::vector<uint32_t> neighbours;
  for (uint32_t t = begin; t < end; ++t) {
    if (!mesh.alive(t)) continue;
    mesh.neighbours(t, neighbours, marks);
    Entry best[kTargetsPerVertex];
    int kept = 0;
    const uint32_t height_t = recorder.height(t);
    for (uint32_t u : neighbours) {
      const double cost = mesh.quadric(t).error_sum(mesh.quadric(u), mesh.position(u));
      const Entry e{(cost + epsilon) * weight(std::max(height_t, recorder.height(u))), t, u};
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
    out = std::copy_n(best, kept, out);
  }
  return size_t(out - first);
}

// Candidates of every live vertex, in vertex order whatever the thread count. Each thread writes its
// chunk of vertices straight into the shared array, at room for kTargetsPerVertex per vertex, and the
// chunks are closed up afterwards: no per-thread arrays (a sixth of the candidates' memory, at the
// builder's peak) and no copy of the first chunk.
class CandidateCollector {
 public:
  CandidateCollector(size_t vertices, unsigned threads) : marks_(threads) {
    for (NeighbourScratch& m : marks_) m.resize(vertices);
  }

  // Into `out`, which has room for kTargetsPerVertex per vertex of `mesh`; returns how many.
  size_t collect(const CollapseMesh& mesh, const CollapseRecorder& recorder, const HeightWeights& weight,
                 double epsilon, std::vector<Entry>& out) {
    const uint32_t n = mesh.vertex_count();
    // Starting a thread costs more than collecting a small round's candidates.
    const unsigned threads = n < kParallelVertices ? 1u : unsigned(marks_.size());
    std::vector<size_t> found(threads);
    const auto run = [&](unsigned i) {
      found[i] = collect_range(mesh, recorder, weight, epsilon, chunk(n, i, threads), chunk(n, i + 1, threads),
                               marks_[i], out.data() + kTargetsPerVertex * size_t(chunk(n, i, threads)));
    };
    std::vector<std::thread> workers;
    for (unsigned i = 1; i < threads; ++i) workers.emplace_back(run, i);
    run(0);
    for (std::thread& w : workers) w.join();
    size_t count = found[0];
    for (unsigned i = 1; i < threads; ++i) {
      const auto chunk_begin = out.begin() + ptrdiff_t(kTargetsPerVertex * size_t(chunk(n, i, threads)));
      std::copy(chunk_begin, chunk_begin + ptrdiff_t(found[i]), out.begin() + ptrdiff_t(count));
      count += found[i];
    }
    return count;
  }

 private:
  static constexpr uint32_t kParallelVertices = 4096;
  static uint32_t chunk(uint32_t n, unsigned i, unsigned threads) { return uint32_t(uint64_t(n) * i / threads); }
  std::vector<NeighbourScratch> marks_;
};

}  // namespace

CollapseForest simplify_balanced(const Mesh& input, const BuildOptions& options) {
  CollapseMesh mesh(input);
  CollapseRecorder recorder(input, mesh, options.deviation);
  const uint32_t start = mesh.alive_vertex_count();
  const uint32_t target = uint32_t(std::clamp<uint64_t>(options.base_vertices, 1, start));  // 0 -> 1: no limit
  const double diagonal = bounds_of(input.positions).diagonal();
  // Keeps zero-error collapses (flat regions) ordered by height too where a round weights height.
  const double epsilon = 1e-10 * diagonal * diagonal;

  const HeightWeights early_weights(kEarlyRounds.height_base), late_weights(kLateRounds.height_base);
  // Sized once: compact() only ever shrinks the vertex count.
  std::vector<Entry> entries(kTargetsPerVertex * size_t(mesh.vertex_count()));
  CandidateCollector collector(mesh.vertex_count(), std::clamp(std::thread::hardware_concurrency(), 1u, 8u));
  std::vector<uint8_t> touched(mesh.vertex_count(), 0);
  std::vector<uint32_t> new_index;
  CollapseSite site;
  while (mesh.alive_vertex_count() > target) {
    const uint32_t alive = mesh.alive_vertex_count();
    const bool late = uint64_t(alive) < uint64_t(kLateRoundsBelowBase) * target;
    const RoundRule& rule = late ? kLateRounds : kEarlyRounds;
    const size_t candidates = collector.collect(mesh, recorder, late ? late_weights : early_weights, epsilon, entries);
    const auto entries_end = entries.begin() + ptrdiff_t(candidates);
    const uint32_t quota = std::min<uint32_t>(alive - target, std::max<uint32_t>(1, uint32_t(alive * rule.share)));
    std::fill(touched.begin(), touched.end(), 0);
    // Usually the quota fills from the cheapest few quota-sized chunks: sort only what is walked.
    uint32_t accepted = 0;
    size_t sorted_end = 0;
    for (size_t i = 0; i < candidates && accepted < quota; ++i) {
      if (i == sorted_end) {
        const size_t chunk_end = std::min(candidates, sorted_end + 2 * size_t(quota) + 1024);
        std::nth_element(entries.begin() + sorted_end, entries.begin() + chunk_end - 1, entries_end, by_key);
        std::sort(entries.begin() + sorted_end, entries.begin() + chunk_end, by_key);
        sorted_end = chunk_end;
      }
      // Entries come in cost order, i.e. scattered over the mesh: fetch a few ahead.
      if (i + 2 * kPrefetchDistance < sorted_end) {
        mesh.prefetch(entries[i + 2 * kPrefetchDistance].t);
        mesh.prefetch(entries[i + 2 * kPrefetchDistance].u);
      }
      if (i + kPrefetchDistance < sorted_end) {
        mesh.prefetch_fan(entries[i + kPrefetchDistance].t);
        mesh.prefetch_fan(entries[i + kPrefetchDistance].u);
      }
      const Entry& e = entries[i];
      if (touched[e.t] || touched[e.u]) continue;
      if (!mesh.check_collapse(e.t, e.u, site)) continue;
      recorder.apply(e.t, e.u, site);
      touched[e.t] = touched[e.u] = 1;
      ++accepted;
    }
    recorder.end_round();
    if (accepted == 0 || accepted < kMinQuotaShare * quota) break;
    if (mesh.alive_vertex_count() < mesh.vertex_count() / 2) {
      recorder.compact(new_index);
      touched.resize(mesh.vertex_count());
    }
    report(options.progress, "simplify", double(start - mesh.alive_vertex_count()) / double(start - target));
  }
  return recorder.finish();
}

}  // namespace pms
