// Hoppe 1997, "View-dependent refinement of progressive meshes", §4: bounding spheres, normal
// cones and deviation spaces D(mu, delta) per vertex-hierarchy node. The closest-point query is
// the classic Voronoi-region test (Ericson, Real-Time Collision Detection §5.1.5).
#include "builder/refinement_info.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "builder/bounds.h"
#include "builder/captured_round.h"
#include "common/parallel.h"
#include "spm/refine_info.h"

namespace pms {
namespace {

constexpr float kPi = std::numbers::pi_v<float>;

struct V3 {  // no default member values: a fan's 32 faces are not cleared for the few it uses
  double x, y, z;
};
V3 load(const float* p) { return {p[0], p[1], p[2]}; }
V3 operator-(V3 a, V3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
V3 operator+(V3 a, V3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
V3 operator*(V3 a, double s) { return {a.x * s, a.y * s, a.z * s}; }
double dot(V3 a, V3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
V3 cross(V3 a, V3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
double length(V3 a) { return std::sqrt(dot(a, a)); }
V3 normalized(V3 a) {
  const double len = length(a);
  return len > 0 ? a * (1.0 / len) : V3{0, 0, 1};
}
// atan2 form: acos of a dot product near 1 is ill-conditioned.
double angle_between(V3 a, V3 b) { return std::atan2(length(cross(a, b)), dot(a, b)); }

struct Cone {
  V3 axis;
  double angle;  // >= pi/2 means "no cone": the node is never culled as back-facing
};

// Smallest cone containing two cones (both axes unit length).
Cone merge_cones(const Cone& a, const Cone& b) {
  if (a.angle >= kPi / 2 || b.angle >= kPi / 2) return {a.axis, kPi};
  const double theta = angle_between(a.axis, b.axis);
  if (theta + b.angle <= a.angle) return a;
  if (theta + a.angle <= b.angle) return b;
  const double angle = (theta + a.angle + b.angle) * 0.5;
  if (angle >= kPi / 2 || theta < 1e-12) return {a.axis, angle >= kPi / 2 ? kPi : angle};
  const double k = (angle - a.angle) / theta;
  const double s = std::sin(theta);
  const V3 axis = normalized(a.axis * (std::sin((1 - k) * theta) / s) + b.axis * (std::sin(k * theta) / s));
  // Slerp rounding can leave an input normal a hair outside: widen by a micro-radian.
  return {axis, angle + 1e-6};
}

RefineBounds to_bounds(double radius, const Cone& cone, double mu, double delta) {
  RefineBounds b;
  b.radius = float(radius);
  b.mu = float(mu);
  b.delta = float(delta);
  b.axis[0] = float(cone.axis.x);
  b.axis[1] = float(cone.axis.y);
  b.axis[2] = float(cone.axis.z);
  b.cone_angle = float(std::min<double>(cone.angle, kPi));
  return b;
}

Cone cone_of(const RefineBounds& b) { return {normalized(V3{b.axis[0], b.axis[1], b.axis[2]}), b.cone_angle}; }

// Rounding a bound to float must not shrink it.
float float_at_least(double value) {
  const float f = float(value);
  return double(f) < value ? std::nextafter(f, INFINITY) : f;
}

}  // namespace

// The faces around the surviving vertex right after the collapse: the surface the node's leaves are
// measured against (bounded, as a fan is; a huge fan only makes the bound larger, never smaller).
struct RefinementInfoBuilder::Fan {
  // A face with what every closest-point query needs of it precomputed: its edges from a and their dot
  // products turn Ericson's six dot products per query into two.
  struct Tri {
    V3 a, ab, ac, n;
    double d;  // plane offset: dot(n, p) - d is the signed distance of p
    double ab_ab, ab_ac, ac_ac;
    V3 rest;  // the two corners other than the fan's centre u, summed

    Tri(V3 a_, V3 b, V3 c)
        : a(a_),
          ab(b - a_),
          ac(c - a_),
          n(normalized(cross(ab, ac))),
          d(dot(n, a_)),
          ab_ab(dot(ab, ab)),
          ab_ac(dot(ab, ac)),
          ac_ac(dot(ac, ac)) {}
    Tri() = default;

    // p minus its closest point on the triangle, `plane` = p's signed distance from it: Ericson's
    // Voronoi-region test (§5.1.5) with ab.bp = ab.ap - ab.ab and its kin in place of the dot products
    // against b and c. Inside, the error is the plane's normal times the distance: exactly zero for a
    // point on a flat patch, where rebuilding the point from barycentric weights left rounding noise
    // that τ = 0 took for a deviation.
    V3 error(V3 p, double plane) const {
      const V3 ap = p - a;
      const double d1 = dot(ab, ap), d2 = dot(ac, ap);
      if (d1 <= 0 && d2 <= 0) return ap;
      const double d3 = d1 - ab_ab, d4 = d2 - ab_ac;
      if (d3 >= 0 && d4 <= d3) return ap - ab;
      const double vc = d1 * d4 - d3 * d2;
      if (vc <= 0 && d1 >= 0 && d3 <= 0) return ap - ab * (d1 / (d1 - d3));
      const double d5 = d1 - ab_ac, d6 = d2 - ac_ac;
      if (d6 >= 0 && d5 <= d6) return ap - ac;
      const double vb = d5 * d2 - d1 * d6;
      if (vb <= 0 && d2 >= 0 && d6 <= 0) return ap - ac * (d2 / (d2 - d6));
      const double va = d3 * d6 - d5 * d4;
      if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
        return ap - ab - (ac - ab) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
      return n * plane;
    }
  };
  static constexpr uint32_t kMax = CapturedRound::kMaxFanFaces;
  Tri tri[kMax];
  uint32_t size = 0;

  // Error vector from p to its closest point on the fan. Starting with the face p is probably
  // closest to (`nearest`, then set to the face found) lets the plane test skip most of the others.
  V3 residual(V3 p, uint32_t& nearest) const {
    double best = INFINITY;
    V3 best_error{};
    uint32_t best_face = nearest;
    for (uint32_t i = 0, f = nearest; i < size; ++i, f = f + 1 == size ? 0 : f + 1) {  // no division per face
      const Tri& tri = this->tri[f];
      const double plane = dot(tri.n, p) - tri.d;
      if (plane * plane >= best) continue;  // the plane distance bounds the triangle distance from below
      const V3 error = tri.error(p, plane);
      const double d2 = dot(error, error);
      if (d2 < best) {
        best = d2;
        best_error = error;
        best_face = f;
      }
    }
    nearest = best_face;
    return best_error;
  }
};

// Hoppe 1997 §4.3: the deviation space D(mu, delta) holding every residual, delta along `axis`.
struct RefinementInfoBuilder::DeviationSpace {
  V3 axis;
  double mu = 0, delta = 0;
  double across_squared = 0;  // residuals' largest squared part across the axis, until settle()
  void add(V3 error) {
    const double along = dot(error, axis);
    delta = std::max(delta, std::abs(along));
    const V3 across = error - axis * along;
    across_squared = std::max(across_squared, dot(across, across));
  }
  // The root of the largest square is the largest root: one sqrt per batch of residuals, not one each.
  void settle() {
    mu = std::max(mu, std::sqrt(across_squared));
    across_squared = 0;
  }
  void add(const DeviationSpace& other) {  // same axis
    delta = std::max(delta, other.delta);
    mu = std::max(mu, other.mu);
  }
  // Hoppe's bound over the whole residual surface, not only the samples: a leaf below a child lies
  // within the child's space of the child's surface, and this collapse moved that surface by at most
  // (about) `moved`, so the leaf lies within their sum of the new surface (triangle inequality). The
  // child's space is first seen from this axis: a vector with perpendicular part <= mu_c and axial
  // part <= delta_c about an axis at angle theta has an axial part <= delta_c cos + mu_c sin about this
  // one, and a perpendicular part <= mu_c + delta_c sin. Never below the child's own numbers either:
  // a parent's bounds contain its children's.
  void add_child(const RefineBounds& child, const DeviationSpace& moved) {
    const V3 child_axis = normalized(V3{child.axis[0], child.axis[1], child.axis[2]});
    const double sin_t = length(cross(child_axis, axis)), cos_t = std::abs(dot(child_axis, axis));
    delta = std::max({delta, double(child.delta), child.delta * cos_t + child.mu * sin_t + moved.delta});
    mu = std::max(mu, child.mu + child.delta * sin_t + moved.mu);
  }
};

RefinementInfoBuilder::RefinementInfoBuilder(const Mesh& mesh, const CollapseMesh& connectivity, size_t max_nodes,
                                             Deviation deviation)
    : positions_(mesh.positions),
      deviation_(deviation),
      scale_(bounds_of(mesh.positions).diagonal()),
      samples_(uint32_t(mesh.vertex_count())) {
  const size_t n = mesh.vertex_count();
  info_.resize(max_nodes);
  survivor_.resize(max_nodes);
  const size_t faces = mesh.face_count();
  BigVector<V3> face_normal(faces);
  for_each_range(faces, 1 << 14, [&](size_t begin, size_t end) {
    for (size_t f = begin; f < end; ++f) {
      const uint32_t* t = &mesh.indices[3 * f];
      const V3 a = load(leaf_position(t[0])), b = load(leaf_position(t[1])), c = load(leaf_position(t[2]));
      face_normal[f] = normalized(cross(b - a, c - a));
    }
  });
  // Each leaf gathers over its own faces (in face order), so vertices run in parallel. The widest
  // normal is the one with the smallest cosine: one acos per vertex. Quantizing searches the
  // octahedral grid around the axis: the costly part.
  for_each_range(n, 1 << 14, [&](size_t begin, size_t end) {
    for (uint32_t v = uint32_t(begin); v < end; ++v) {
      V3 axis{};
      double radius_squared = 0;
      const V3 p = load(leaf_position(v));
      connectivity.for_each_live_face(v, [&](uint32_t f, uint32_t slot) {
        axis = axis + face_normal[f];
        // v's sphere reaches the far ends of its two edges.
        for (uint32_t k = 1; k <= 2; ++k) {
          const V3 e = load(leaf_position(mesh.indices[3 * size_t(f) + (slot + k) % 3])) - p;
          radius_squared = std::max(radius_squared, dot(e, e));
        }
      });
      axis = normalized(axis);
      double min_cos = 1;
      connectivity.for_each_live_face(
          v, [&](uint32_t f, uint32_t) { min_cos = std::min(min_cos, dot(axis, face_normal[f])); });
      const Cone cone{axis, std::acos(std::clamp(min_cos, -1.0, 1.0)) + 1e-6};
      info_[v] = quantize_refine(to_bounds(std::sqrt(radius_squared), cone, 0, 0), scale_);
      survivor_[v] = v;
    }
  });
}

void RefinementInfoBuilder::merge_leaves(uint32_t s, uint32_t, uint32_t u_node, uint32_t t, uint32_t u) {
  survivor_[s] = survivor_[u_node];
  samples_.merge(t, u);
}

void RefinementInfoBuilder::compact(const std::vector<uint32_t>& new_index) { samples_.compact(new_index); }

void RefinementInfoBuilder::compute(uint32_t s, uint32_t t_node, uint32_t u_node, std::span<const uint32_t> corners,
                                    std::span<const uint32_t> samples) {
  const RefineBounds bt = dequantize_refine(info_[t_node], scale_);
  const RefineBounds bu = dequantize_refine(info_[u_node], scale_);
  const double shift = length(load(leaf_position(survivor_[t_node])) - load(leaf_position(survivor_[s])));
  // v_u sits where v_s sits, so only v_t's sphere moves.
  const double radius = std::max<double>(bu.radius, bt.radius + shift) * (1 + 1e-6);
  RefineBounds bounds = to_bounds(radius, merge_cones(cone_of(bt), cone_of(bu)), 0, 0);
  // delta is measured along the axis every consumer decodes; without a cone none is stored, and the
  // whole residual has to count as mu (delta is kept, which only refines more).
  RefineInfo info = quantize_refine(bounds, scale_);
  const RefineBounds frame = dequantize_refine(info, scale_);
  const bool has_axis = frame.cone_angle < kPi / 2;
  DeviationSpace space{has_axis ? normalized(V3{frame.axis[0], frame.axis[1], frame.axis[2]}) : V3{0, 0, 1}};
  const Fan fan = fan_of(corners, survivor_[s]);
  DeviationSpace moved{space.axis};
  if (fan.size > 0) {
    add_leaf_samples(fan, samples, space);
    add_moved_surface(fan, survivor_[t_node], moved);
  }
  if (deviation_ == Deviation::bound) {
    space.add_child(bt, moved);
    space.add_child(bu, moved);
  } else {  // the moved surface counts once, not on top of each child's space
    space.add(moved);
    const DeviationSpace unmoved{space.axis};
    space.add_child(bt, unmoved);
    space.add_child(bu, unmoved);
  }
  bounds.mu = float_at_least(has_axis ? space.mu : std::hypot(space.mu, space.delta));
  bounds.delta = float_at_least(space.delta);
  // Only the deviation is new: its two lengths go into the info above, as quantize_refine stores them.
  info.mu = encode_length(bounds.mu, scale_);
  info.delta = encode_length(bounds.delta, scale_);
  info_[s] = info;
}

RefinementInfoBuilder::Fan RefinementInfoBuilder::fan_of(std::span<const uint32_t> corners, uint32_t u_leaf) const {
  Fan fan;
  for (size_t c = 0; c + 3 <= corners.size() && fan.size < Fan::kMax; c += 3) {
    const uint32_t* leaves = &corners[c];
    Fan::Tri& tri = fan.tri[fan.size++];
    tri = Fan::Tri(load(leaf_position(leaves[0])), load(leaf_position(leaves[1])), load(leaf_position(leaves[2])));
    tri.rest = {};
    for (int k = 0; k < 3; ++k)
      if (leaves[k] != u_leaf) tri.rest = tri.rest + load(leaf_position(leaves[k]));
  }
  return fan;
}

// Hoppe's own measure: sampled leaves of u's subtree against the new fan. It sees what the chain of
// add_child() misses, such as a child's surface changed by its neighbours' collapses after its bounds
// were computed.
void RefinementInfoBuilder::add_leaf_samples(const Fan& fan, std::span<const uint32_t> samples,
                                             DeviationSpace& space) const {
  uint32_t nearest = 0;  // samples come in runs from one child's side: the last face found is a good start
  // Samples are scattered over the input: fetch a few ahead, the query itself is mostly a cache miss.
  constexpr size_t kAhead = 4;
  for (size_t i = 0; i < std::min(kAhead, samples.size()); ++i) __builtin_prefetch(leaf_position(samples[i]));
  for (size_t i = 0; i < samples.size(); ++i) {
    if (i + kAhead < samples.size()) __builtin_prefetch(leaf_position(samples[i + kAhead]));
    space.add(fan.residual(load(leaf_position(samples[i])), nearest));
  }
  space.settle();
}

// How far this collapse moved the surface: v_t itself, and each fan face (u, a, b) at the centroid of
// (v_t, a, b), the face it was if it was v_t's (if it was u's, a point between the two surfaces: a
// little more, never less). A vertex lying on the coarse surface does not mean its faces do: v_t on a
// flat fan with a bumpy ring measures 0.
void RefinementInfoBuilder::add_moved_surface(const Fan& fan, uint32_t t_leaf, DeviationSpace& space) const {
  const V3 p_t = load(leaf_position(t_leaf));  // v_t's position: the leaf that carries it
  uint32_t nearest = 0;
  space.add(fan.residual(p_t, nearest));
  for (uint32_t f = 0; f < fan.size; ++f) {
    nearest = f;  // the face it came from
    space.add(fan.residual((fan.tri[f].rest + p_t) * (1.0 / 3), nearest));
  }
  space.settle();
}

}  // namespace pms
