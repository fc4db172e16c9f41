// Nested refinement info: Hoppe 1997 §4's bounds, rounded up onto the lattices of
// spm/nested_info.h below each node's parent. A parent's bounds hold its children's (refinement_info.cpp:
// r(v_s) >= r(v_u), r(v_t) + |p_t - p_s|; the merged cone holds both cones; (mu, delta) of v_s is at least
// each child's re-expressed on v_s's axis), so the parent's own value is always an entry that holds the
// child's, and the entries below it cost a child a few bits each (docs/internals.md, "Split records").
#include "builder/nested_refine_info.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "common/parallel.h"
#include "spm/dequantize_inline.h"
#include "spm/nested_info.h"
#include "spm/refine_info.h"

namespace pms {
namespace {

constexpr size_t kParallelNodes = size_t(1) << 14;                     // fewer run inline
constexpr double kConeUnit = std::numbers::pi / 2 / (kConeSteps + 1);  // one step of RefineInfo::cone_angle

double angle_between(const float a[3], const float b[3]) {
  const double cx = double(a[1]) * b[2] - double(a[2]) * b[1], cy = double(a[2]) * b[0] - double(a[0]) * b[2],
               cz = double(a[0]) * b[1] - double(a[1]) * b[0];
  return std::atan2(std::sqrt(cx * cx + cy * cy + cz * cz),
                    double(a[0]) * b[0] + double(a[1]) * b[1] + double(a[2]) * b[2]);
}

// The stored half at or above a length (relative to the scale, as RefineInfo stores it).
uint16_t length_up(double length) {
  const float f = float(length);
  return encode_length(double(f) < length ? std::nextafter(f, INFINITY) : f, 1);
}

// `own` with its axis on the nearest octahedral point whose coordinates are multiples of 2^kAxisSnapBits:
// the cone widened by the move e, and (mu, delta) re-expressed about the new axis (a vector with parts
// <= mu across and <= delta along one axis has parts <= mu + delta sin e and delta |cos e| + mu sin e about
// an axis at angle e: DeviationSpace::add_child). A cone the move would open to pi/2 stays where it is.
RefineInfo snap_axis(const RefineInfo& own) {
  using dequantize_detail::decode_axis, dequantize_detail::decode_cone_angle;
  if (own.cone_angle == kNoCone) return own;
  float axis[3];
  decode_axis(own.cone_x, own.cone_y, axis);
  constexpr int kStep = 1 << kAxisSnapBits, kLimit = kAxisSteps / kStep * kStep;
  const auto snap = [&](uint16_t q, bool up) {
    const int v = int16_t(q);
    return uint16_t(int16_t(
        std::clamp((v >= 0 ? v / kStep : -((-v + kStep - 1) / kStep)) * kStep + (up ? kStep : 0), -kLimit, kLimit)));
  };
  // Rank the candidates by cosine (cheap); only the winner's angle needs atan2.
  RefineInfo best = own;
  double best_cos = -INFINITY;
  float best_axis[3] = {0, 0, 1};
  for (int i = 0; i < 4; ++i) {
    RefineInfo candidate = own;
    candidate.cone_x = snap(own.cone_x, i & 1);
    candidate.cone_y = snap(own.cone_y, i & 2);
    float snapped[3];
    decode_axis(candidate.cone_x, candidate.cone_y, snapped);
    const double length =
        std::sqrt(double(snapped[0]) * snapped[0] + double(snapped[1]) * snapped[1] + double(snapped[2]) * snapped[2]);
    const double cosine =
        (double(snapped[0]) * axis[0] + double(snapped[1]) * axis[1] + double(snapped[2]) * axis[2]) / length;
    if (cosine > best_cos) best_cos = cosine, best = candidate, std::copy_n(snapped, 3, best_axis);
  }
  if (best.cone_x == own.cone_x && best.cone_y == own.cone_y) return own;  // on the grid already
  const double best_error = angle_between(best_axis, axis);
  const double angle =
      double(decode_cone_angle(own.cone_angle)) + best_error + 1e-6;  // 1e-6: float slack, as quantize_refine
  auto units = uint32_t(std::ceil(angle / kConeUnit));
  while (units <= kConeSteps && double(decode_cone_angle(uint16_t(units))) < angle) ++units;
  if (units > kConeSteps) return own;
  best.cone_angle = uint16_t(units);
  const double mu = float_from_half(own.mu), delta = float_from_half(own.delta);
  const double s = std::sin(best_error), c = std::abs(std::cos(best_error));
  best.mu = length_up(mu + delta * s);
  best.delta = length_up(std::max(delta, delta * c + mu * s));
  return best;
}

// The lowest entry below `parent` that holds `own`, or `own` itself when none does (0 stays 0).
uint16_t nested_length(uint16_t parent, uint16_t own, uint32_t codes_per_step) {
  if (own == 0) return 0;
  const uint32_t k = length_entry(parent, own, codes_per_step);
  return k == kNoEntry ? own : uint16_t(length_at_entry(parent, k, codes_per_step));
}
uint16_t nested_angle(uint16_t parent, uint16_t own) {
  if (own == kNoCone || parent == kNoCone) return own;
  const uint32_t k = angle_entry(parent, own);
  return k == kNoEntry ? own : uint16_t(angle_at_entry(parent, k));
}

// The child's bounds, its axis snapped already, nested under its parent's final ones (as a client holds
// them: as_sent).
RefineInfo nest(const RefineInfo& parent_final, const RefineInfo& snapped) {
  if (never_refines(snapped)) return snapped;
  const RefineInfo parent = as_sent(parent_final);
  RefineInfo info = snapped;
  info.radius = nested_length(parent.radius, info.radius, kRadiusCodesPerStep);
  info.mu = nested_length(parent.mu, info.mu, kMuCodesPerStep);
  info.delta = nested_length(parent.delta, info.delta, kDeltaCodesPerStep);
  info.cone_angle = nested_angle(parent.cone_angle, info.cone_angle);
  return info;
}

}  // namespace

void nest_refine_info(CollapseForest& forest) {
  // Where a child's axis snaps does not depend on its parent: every node's at once.
  std::vector<uint8_t> is_root(forest.node_count(), 0);
  for (const uint32_t root : forest.root_node) is_root[root] = 1;
  for_each_range(forest.node_count(), kParallelNodes, [&](size_t begin, size_t end) {
    for (size_t node = begin; node < end; ++node)
      if (!is_root[node] && !never_refines(forest.info[node])) forest.info[node] = snap_axis(forest.info[node]);
  });
  // Collapse k's node lies above every earlier collapse's, so going down from the last collapse nests each
  // node after its parent is final.
  for (size_t k = forest.child_t.size(); k-- > 0;) {
    const RefineInfo parent = forest.info[forest.leaf_count + k];
    for (const uint32_t child : {forest.child_t[k], forest.child_u[k]})
      forest.info[child] = nest(parent, forest.info[child]);
  }
}

}  // namespace pms
