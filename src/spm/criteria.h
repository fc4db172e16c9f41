// The view-dependent refinement criterion qrefine(v) of Hoppe 1997 §4 (kim-lee-kobbelt 2005 §5.3 use
// it unchanged): refine v when its bounding sphere meets the view frustum, the surface below it is not
// entirely back-facing, and its deviation space projects to more than τ pixels on screen.
//
// Every mode (local refinement, the sender-driven server, the receiver-driven client, DAG traversal)
// evaluates this one function on the same decoded numbers — RefineBounds from dequantize_refine() of the
// RefineInfo every mode shares, the node position every mode holds, and a ViewCriteria made by
// make_criteria() from the same make_view() — so they agree on the refined mesh of a view
// (property 3 of docs/architecture.md, "Correctness properties").
// Shared with the browser build: plain arithmetic, single-threaded.
#pragma once
#include <cstdint>

#include "common/camera.h"
#include "spm/refine_info.h"

namespace pms {

// What qrefine needs of one view, derived once per frame.
struct ViewCriteria {
  float planes[6][4] = {};  // ViewParams::planes: inside when a*x + b*y + c*z + d >= 0
  float eye[3] = {0, 0, 0};
  float kappa2 = 0;  // kappa² = (τ · pixel_angle)², Hoppe 1997 §4.3
};

// `tolerance_px` = τ >= 0 (pms::Error otherwise).
ViewCriteria make_criteria(const ViewParams& view, float tolerance_px);

// One hierarchy node as qrefine reads it, decoded once: position p, the RefineBounds of the node.
struct NodeCriteria {
  float p[3] = {0, 0, 0};
  float radius = 0;
  float mu2 = 0, delta2 = 0;    // mu², delta²
  float axis[3] = {0, 0, 1};    // normal-cone axis = the direction delta is measured along
  float cos_a = -1, sin_a = 0;  // cone half-angle; cos_a <= 0: the cone test never culls
};

NodeCriteria node_criteria(const float position[3], const RefineBounds& bounds);

// The three tests, exposed for tests and tools; qrefine() is their conjunction.
// Sphere entirely on the outer side of one of the six planes.
bool outside_frustum(const ViewCriteria& view, const NodeCriteria& node);
// Every point q of the sphere and every normal n of the cone have n·(q − e) > 0: nothing below the node
// can face the eye. Conservative (the sphere radius is accounted for, plus a relative float margin), so a
// front-facing input face below the node is never culled.
bool back_facing(const ViewCriteria& view, const NodeCriteria& node);
// Hoppe 1997 §4.3 with d = p − e: mu² > kappa²‖d‖²  or  delta²(‖d‖² − (d·n)²) > kappa²‖d‖⁴. Strict, so
// a real leaf (mu = delta = 0) never asks to be refined, even at τ = 0.
bool screen_error_exceeds(const ViewCriteria& view, const NodeCriteria& node);

// qrefine(v) = screen_error_exceeds ∧ ¬outside_frustum ∧ ¬back_facing (cheapest and most selective first).
bool qrefine(const ViewCriteria& view, const NodeCriteria& node);
inline bool qrefine(const ViewCriteria& view, const float position[3], const RefineBounds& bounds) {
  return qrefine(view, node_criteria(position, bounds));
}

// How visible a node's error is when qrefine wants it split (0 when it does not): the larger of Hoppe's
// two deviation terms over the squared eye distance, > 0 whenever qrefine holds. A sender fixes the most
// visible error first.
float refinement_priority(const ViewCriteria& view, const NodeCriteria& node);

}  // namespace pms
