// The arithmetic of qrefine (Hoppe 1997 §4), inline for the adaptation loop, which evaluates it for
// every node it reaches: as a call it cost a fifth of a steady frame. criteria.cpp exposes the same
// functions out of line; every caller compiles the same expressions, without contraction (no FMA in the
// build), so every mode still gets the same answers.
#pragma once
#include <algorithm>
#include <cmath>
#include <vector>

#include "spm/criteria.h"
#include "spm/dequantize_inline.h"

namespace pms::criteria_detail {
// Float slack, relative to the eye distance, for the two culling tests: rounding in the planes, the
// decoded cone axis and cos/sin of its angle is ~1e-7 of the distance; culling a little less is safe.
constexpr float kCullSlack = 1e-5f;

inline float dot3(const float a[3], const float b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

// node_criteria but the cone's cosine and sine (left as for a cone that never culls).
inline NodeCriteria node_criteria_without_cone(const float position[3], const RefineBounds& bounds) {
  NodeCriteria n;
  for (int k = 0; k < 3; ++k) {
    n.p[k] = position[k];
    n.axis[k] = bounds.axis[k];
  }
  n.radius = bounds.radius;
  n.mu2 = bounds.mu * bounds.mu;
  n.delta2 = bounds.delta * bounds.delta;
  return n;
}

// The cosine and sine node_criteria gives a cone of `units` (<= kConeSteps) steps, worked out by
// node_criteria itself the first time any is asked for (criteria.cpp), so a lookup gives the same bits.
struct ConeTrig {
  float cos_a, sin_a;
};
std::vector<ConeTrig> cone_trig_table();  // kConeSteps + 1 entries
inline const ConeTrig& cone_trig(uint16_t units) {
  static const std::vector<ConeTrig> table = cone_trig_table();
  return table[units];
}

// node_criteria(position, dequantize_refine(info, scale)), for the adaptation loop, which decodes a
// node when its walk first reaches it: inline, with the cone's cosine and sine looked up, and given
// `effective` = dequantize_detail::effective_scale(scale), which the loop works out once.
inline NodeCriteria node_criteria_inline(const float position[3], const RefineInfo& info, float effective) {
  const RefineBounds bounds = dequantize_detail::dequantize_refine_scaled(info, effective);
  if (info.cone_angle > kConeSteps) return node_criteria(position, bounds);  // no cone, or not canonical
  NodeCriteria n = node_criteria_without_cone(position, bounds);
  const ConeTrig& trig = cone_trig(info.cone_angle);
  n.cos_a = trig.cos_a;
  n.sin_a = trig.sin_a;
  return n;
}

// What the tests share for one node: d = p − e and ‖d‖². Each test takes it ready, so a caller running
// several computes it once, with the values each test computed alone. a·d (a the cone axis, along which
// delta is measured) stays in the tests that need it: both settle most nodes before it.
struct EyeOffset {
  float d[3];
  float d2;
};

[[gnu::always_inline]] inline EyeOffset eye_offset(const ViewCriteria& view, const NodeCriteria& node) {
  EyeOffset o;
  for (int k = 0; k < 3; ++k) o.d[k] = node.p[k] - view.eye[k];
  o.d2 = dot3(o.d, o.d);
  return o;
}

// The frustum test, and when it passes `lowest` = the smallest of the six plane values it computed (the
// adaptation walk bounds the children's values with it: SelectiveRefinement::walk_qrefine).
[[gnu::always_inline]] inline bool outside_frustum_inline(const ViewCriteria& view, const NodeCriteria& node,
                                                          const EyeOffset& o, float& lowest) {
  const float slack = node.radius + kCullSlack * std::sqrt(o.d2);
  lowest = INFINITY;
  for (const float* plane : view.planes) {
    const float value = dot3(plane, node.p) + plane[3];
    if (value < -slack) return true;
    lowest = std::min(lowest, value);
  }
  return false;
}

[[gnu::always_inline]] inline bool outside_frustum_inline(const ViewCriteria& view, const NodeCriteria& node,
                                                          float& lowest) {
  return outside_frustum_inline(view, node, eye_offset(view, node), lowest);
}

[[gnu::always_inline]] inline bool outside_frustum_inline(const ViewCriteria& view, const NodeCriteria& node) {
  float lowest;
  return outside_frustum_inline(view, node, lowest);
}

// With d = p − e, θ = angle(a, d) and α the cone half-angle, min over the cone of n·d is
// ‖d‖ cos(θ + α) = (a·d) cos α − ‖a × d‖ sin α, and min over the sphere of n·(q − e) is n·d − r.
// Hoppe's test (a·d > 0 ∧ (a·d)² > ‖d‖² sin²α) is this with r = 0.
[[gnu::always_inline]] inline bool back_facing_inline(const NodeCriteria& node, const EyeOffset& o) {
  if (node.cos_a <= 0) return false;
  const float along = dot3(node.axis, o.d);
  // The bound below is at most (a·d) cos α, rounding included (it subtracts a term >= 0 and compares
  // with r plus a term >= 0, and rounding is monotone), so this skips the square roots with the same
  // answer; cos α <= 1 makes it hold whenever a·d <= r.
  if (along * node.cos_a <= node.radius) return false;
  const float* a = node.axis;
  const float* d = o.d;
  const float c[3] = {a[1] * d[2] - a[2] * d[1], a[2] * d[0] - a[0] * d[2], a[0] * d[1] - a[1] * d[0]};
  const float across = std::sqrt(dot3(c, c));  // ‖a × d‖: accurate where sqrt(‖d‖² − (a·d)²) cancels
  const float distance = std::sqrt(o.d2);
  return along * node.cos_a - across * node.sin_a > node.radius + kCullSlack * distance;
}

[[gnu::always_inline]] inline bool back_facing_inline(const ViewCriteria& view, const NodeCriteria& node) {
  return back_facing_inline(node, eye_offset(view, node));
}

[[gnu::always_inline]] inline bool screen_error_exceeds_inline(const ViewCriteria& view, const NodeCriteria& node,
                                                               const EyeOffset& o) {
  const float bound = view.kappa2 * o.d2;  // kappa² ‖d‖²
  if (node.mu2 > bound) return true;
  // δ² ≤ κ²‖d‖² settles the second test without a·d: ‖d‖² − (d·a)² ≤ ‖d‖², so δ²(‖d‖² − (d·a)²) ≤
  // κ²‖d‖⁴ (products of values >= 0, and rounding is monotone), the same answer.
  if (node.delta2 <= bound) return false;
  const float along = dot3(o.d, node.axis);
  return node.delta2 * (o.d2 - along * along) > bound * o.d2;
}

[[gnu::always_inline]] inline bool screen_error_exceeds_inline(const ViewCriteria& view, const NodeCriteria& node) {
  return screen_error_exceeds_inline(view, node, eye_offset(view, node));
}

// The screen error over the threshold, squared (>= 1 where screen_error_exceeds_inline holds, up to rounding):
// how near a node is to needing a split. Grows as the square of 1 / the eye distance.
[[gnu::always_inline]] inline float screen_ratio2_inline(const ViewCriteria& view, const NodeCriteria& node,
                                                         const EyeOffset& o) {
  const float d2 = std::max(o.d2, 1e-30f);
  const float along = dot3(o.d, node.axis);
  const float bound = std::max(view.kappa2 * d2, 1e-30f);
  return std::max(node.mu2, node.delta2 * (d2 - along * along) / d2) / bound;
}

[[gnu::always_inline]] inline bool qrefine_inline(const ViewCriteria& view, const NodeCriteria& node,
                                                  const EyeOffset& o) {
  float lowest;
  return screen_error_exceeds_inline(view, node, o) && !outside_frustum_inline(view, node, o, lowest) &&
         !back_facing_inline(node, o);
}

[[gnu::always_inline]] inline bool qrefine_inline(const ViewCriteria& view, const NodeCriteria& node) {
  return qrefine_inline(view, node, eye_offset(view, node));
}

[[gnu::always_inline]] inline float priority_inline(const ViewCriteria& view, const NodeCriteria& node) {
  const EyeOffset o = eye_offset(view, node);
  if (!qrefine_inline(view, node, o)) return 0;
  const float d2 = std::max(o.d2, 1e-30f);
  const float along = dot3(o.d, node.axis);
  const float error = std::max(node.mu2 * d2, node.delta2 * (d2 - along * along)) / (d2 * d2);
  return std::max(error, 1e-30f);  // qrefine held: stay > 0 even when it underflows
}

}  // namespace pms::criteria_detail
