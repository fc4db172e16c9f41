// Nested refinement info (issue 19, the children's refinement info on E5's close view): what a child's
// bounds cost when they are taken from a short list of fractions of its parent's, and what that costs in
// selectivity. A parent's bounds hold its children's (refinement_info.cpp: r(v_s) >= r(v_t) + |p_t - p_s|,
// r(v_u); the merged cone holds both cones; (mu, delta) of v_s is at least each child's re-expressed on
// v_s's axis), so a child may claim its true value rounded UP to the next entry of a log lattice below its
// parent's value, and every bound stays conservative. The cone axis is the costly part (~6.5 bits per
// child as coded today): a child may take its parent's axis, its cone and (mu, delta) re-expressed about
// that axis (Hoppe 1997 §4.3; the same re-expression as DeviationSpace::add_child), when that costs few
// lattice steps. The bits are counted with static Huffman codes per context, fitted over the whole model
// as SplitCodec fits its tables; topology and geometry come from the real codec over the nested values.
// PMSTREAM_RECORD_BITS_PMS=FILE.pms measures that file, else the bunny (with issue 18's four cameras).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>
#include <string>
#include <vector>

#include "bench/bench_refine.h"
#include "bench/split_record_bits.h"
#include "common/prefix_code.h"
#include "record_bits_model.h"
#include "spm/adapt.h"
#include "spm/split_codec.h"

namespace pms::bench {
namespace {

constexpr double kConeUnit = std::numbers::pi / 2 / (kConeSteps + 1);  // one step of RefineInfo::cone_angle
constexpr uint32_t kBits = 16;

// Lattice entries per octave below the parent's value, per field; kOctaves octaves of entries, the parent's
// own value first; below the last, the escapes: symbol kOctaves * per_octave for 0, the next one for the
// exact value (11 raw bits for a length, 10 for an angle).
struct Lattice {
  uint32_t radius, mu, delta, angle;
};
constexpr uint32_t kOctaves = 12;
struct Variant {
  const char* name;
  Lattice per_octave;
  int inherit_steps;   // a child takes its parent's axis when that costs at most this many lattice steps
                       // over mu, delta and angle together; -1: never
  bool radius_shift;   // v_t's radius against r(v_s) - |p_t - p_s| (the grid's lower bound), not r(v_s)
  uint32_t axis_drop;  // an own axis snapped to octahedral coordinates that are multiples of 2^axis_drop
};

// What one child's nested info is, field by field: the lattice entry or an escape (Lattice above).
struct ChildSymbols {
  uint32_t radius = 0, mu = 0, delta = 0, angle = 0;
  bool own_axis = false, no_cone = false, absolute = false;  // absolute: the parent never refines
};

uint16_t kept_up(uint32_t half) { return uint16_t(std::min<uint32_t>((half + 15) & ~15u, 0x7C00)); }
// The smallest stored length (kept bits) at or above `value` (relative to the model's scale).
uint16_t length_up(double value) {
  if (!(value > 0)) return 0;
  uint16_t h = kept_up(half_from_float_up(float(value)));
  while (h < 0x7C00 && double(float_from_half(h)) < value) h = kept_up(h + 1u);
  return h;
}
double rel(uint16_t half) { return float_from_half(half); }

struct Pick {
  uint32_t symbol;
  uint16_t value;
};
// The last lattice entry below `base` that still holds `value`; an escape for 0, or with the exact value
// when the entry after the last one would hold it too, or when the base cannot.
Pick lattice_length(double value, uint16_t base, uint32_t per_octave) {
  const uint32_t escape = kOctaves * per_octave;
  const auto entry = [&](uint32_t k) { return length_up(rel(base) * std::exp2(-double(k) / per_octave)); };
  if (!(value > 0)) return {escape, 0};
  if (base == 0 || base >= 0x7C00 || rel(base) < value) return {escape + 1, length_up(value)};
  uint32_t k = 0;
  while (k + 1 <= escape && rel(entry(k + 1)) >= value) ++k;
  if (k == escape) return {escape + 1, length_up(value)};
  return {k, entry(k)};
}
Pick lattice_angle(uint32_t needed, uint16_t base, uint32_t per_octave) {
  const uint32_t escape = kOctaves * per_octave;
  const auto entry = [&](uint32_t k) { return uint16_t(std::ceil(base * std::exp2(-double(k) / per_octave))); };
  if (needed == 0) return {escape, 0};
  if (base == kNoCone || base < needed) return {escape + 1, uint16_t(needed)};
  uint32_t k = 0;
  while (k + 1 <= escape && entry(k + 1) >= needed) ++k;
  if (k == escape) return {escape + 1, uint16_t(needed)};
  return {k, entry(k)};
}

double angle_between(const float a[3], const float b[3]) {
  const double cx = double(a[1]) * b[2] - double(a[2]) * b[1], cy = double(a[2]) * b[0] - double(a[0]) * b[2],
               cz = double(a[0]) * b[1] - double(a[1]) * b[0];
  return std::atan2(std::sqrt(cx * cx + cy * cy + cz * cz),
                    double(a[0]) * b[0] + double(a[1]) * b[1] + double(a[2]) * b[2]);
}

float angle_to(const RefineInfo& info, const float axis[3]) {
  return float(angle_between(dequantize_refine(info, 1).axis, axis));
}

// `own` with its axis moved to the nearest point of the coarser octahedral grid: the cone widened by the
// move and (mu, delta) re-expressed about the new axis (a vector with perpendicular part <= mu and axial
// part <= delta about an axis at angle e has parts <= mu + delta sin e and delta cos e + mu sin e about
// the other, as DeviationSpace::add_child re-expresses a child's space).
struct Snapped {
  RefineInfo info;
  double mu, delta;
};
Snapped snap_axis(const RefineInfo& own, uint32_t drop) {
  Snapped out{own, rel(own.mu), rel(own.delta)};
  if (drop == 0 || own.cone_angle == kNoCone) return out;
  const RefineBounds b = dequantize_refine(own, 1);
  const int step = 1 << drop, limit = (kAxisSteps / step) * step;
  double best = INFINITY;
  for (int i = 0; i < 4; ++i) {
    RefineInfo c = own;
    const int x = int16_t(own.cone_x), y = int16_t(own.cone_y);
    const auto snap = [&](int v, bool up) {
      return std::clamp(int(std::floor(double(v) / step)) * step + (up ? step : 0), -limit, limit);
    };
    c.cone_x = uint16_t(int16_t(snap(x, i & 1)));
    c.cone_y = uint16_t(int16_t(snap(y, i & 2)));
    const double e = angle_to(c, b.axis);
    if (e < best) best = e, out.info = c;
  }
  const double s = std::sin(best), c = std::cos(best);
  out.mu = rel(own.mu) + rel(own.delta) * s;
  out.delta = std::max(rel(own.delta), rel(own.delta) * c + rel(own.mu) * s);
  const auto needed = uint32_t(std::ceil((b.cone_angle + best + 1e-6) / kConeUnit));
  if (needed > kConeSteps) out.info.cone_angle = kNoCone, out.info.cone_x = out.info.cone_y = 0;
  else out.info.cone_angle = uint16_t(needed);
  return out;
}

// |p_t - p_s| from below, from the grid positions the client holds (each within a step per axis of the
// float one), in the refinement info's unit.
double shift_lower_bound(const ModelData& model, std::span<const uint32_t> q, uint32_t s, uint32_t t) {
  double grid = 0, error = 0;
  for (int k = 0; k < 3; ++k) {
    const double step = (double(model.bbox_max[k]) - model.bbox_min[k]) / double((1u << kBits) - 1);
    const double d = (double(q[3 * size_t(t) + k]) - double(q[3 * size_t(s) + k])) * step;
    grid += d * d, error += step * step;
  }
  return std::max(0.0, std::sqrt(grid) - 1.001 * std::sqrt(error)) / model.scale;
}

Lattice escapes(const Variant& v) {
  const Lattice& o = v.per_octave;
  return {kOctaves * o.radius, kOctaves * o.mu, kOctaves * o.delta, kOctaves * o.angle};
}

struct Nested {
  std::vector<RefineInfo> info;
  std::vector<ChildSymbols> symbols;  // per node (roots and nodes that never refine: unused)
  size_t children = 0, inherited = 0, escapes = 0;
};

// Top down (parents precede children in the packed order): each node's values nested under its parent's
// final ones. Every final value is at least the node's own (same axis) or its own re-expressed about the
// parent's axis, and at most the parent's, so the lattice's first entry always holds it.
Nested nest(const ModelData& model, std::span<const uint32_t> q, const Variant& v) {
  Nested out{{model.refine.begin(), model.refine.end()}, std::vector<ChildSymbols>(model.node_count()), 0, 0, 0};
  const Lattice& o = v.per_octave;
  const Lattice e = escapes(v);
  for (uint32_t n = model.root_count; n < model.node_count(); ++n) {
    if (never_refines(model.refine[n])) continue;
    const Snapped snapped = snap_axis(model.refine[n], v.axis_drop);
    const RefineInfo own = snapped.info;
    const uint32_t p = model.parent[n];
    const RefineInfo parent = out.info[p];
    ChildSymbols& sym = out.symbols[n];
    ++out.children;
    if (never_refines(parent)) {  // sent as zeros: nothing to nest under
      sym = {e.radius + 1, e.mu + 1, e.delta + 1, e.angle + 1, true, own.cone_angle == kNoCone, true};
      out.escapes += 4;
      continue;
    }
    const RefineInfo orig = model.refine[n];
    const RefineBounds bp = dequantize_refine(parent, 1), bn = dequantize_refine(orig, 1);
    double radius_base = rel(parent.radius);
    if (v.radius_shift && n == model.first_child[p])
      radius_base = std::max(0.0, radius_base - shift_lower_bound(model, q, p, n));
    const Pick radius = lattice_length(rel(own.radius), length_up(radius_base), o.radius);
    // Own axis.
    Pick mu = lattice_length(snapped.mu, parent.mu, o.mu), delta = lattice_length(snapped.delta, parent.delta, o.delta);
    Pick angle =
        own.cone_angle == kNoCone ? Pick{e.angle, kNoCone} : lattice_angle(own.cone_angle, parent.cone_angle, o.angle);
    bool inherit = false;
    if (v.inherit_steps >= 0 && parent.cone_angle != kNoCone && orig.cone_angle != kNoCone) {
      const double theta = angle_between(bn.axis, bp.axis), s = std::sin(theta), c = std::abs(std::cos(theta));
      const double mu_about = std::max(rel(orig.mu), std::min(rel(orig.mu) + rel(orig.delta) * s, rel(parent.mu)));
      const double delta_about =
          std::max(rel(orig.delta), std::min(rel(orig.delta) * c + rel(orig.mu) * s, rel(parent.delta)));
      auto needed = uint32_t(std::ceil((theta + bn.cone_angle + 1e-6) / kConeUnit));
      needed = std::max<uint32_t>(std::min<uint32_t>(needed, parent.cone_angle), orig.cone_angle);
      const Pick mu_i = lattice_length(mu_about, parent.mu, o.mu),
                 delta_i = lattice_length(delta_about, parent.delta, o.delta);
      const Pick angle_i = lattice_angle(needed, parent.cone_angle, o.angle);
      const int cost =
          int(mu.symbol + delta.symbol + angle.symbol) - int(mu_i.symbol + delta_i.symbol + angle_i.symbol);
      if (cost <= v.inherit_steps) inherit = true, mu = mu_i, delta = delta_i, angle = angle_i;
    }
    RefineInfo& info = out.info[n];
    info.radius = radius.value, info.mu = mu.value, info.delta = delta.value;
    info.cone_angle = angle.value;
    info.cone_x = inherit ? parent.cone_x : own.cone_x, info.cone_y = inherit ? parent.cone_y : own.cone_y;
    sym = {radius.symbol, mu.symbol, delta.symbol, angle.symbol, !inherit, !inherit && own.cone_angle == kNoCone,
           false};
    out.inherited += inherit;
    out.escapes += (radius.symbol > e.radius) + (mu.symbol > e.mu) + (delta.symbol > e.delta) +
                   (angle.symbol > e.angle && own.cone_angle != kNoCone);
  }
  return out;
}

// The children's info of each split as symbols in context slots plus raw bits, Huffman per slot.
class InfoBits {
 public:
  InfoBits(const ModelData& model, const Nested& nested, const Variant& v) : model_(model), nested_(nested), v_(v) {
    for (uint32_t d = 0; d < model.node_count(); ++d) max_depth_ = std::max(max_depth_, model.id(d).depth());
    for (uint32_t s : model.split_order) emit(s, [&](uint32_t slot, uint32_t sym, uint32_t) { count(slot, sym); });
    for (auto& [slot, counts] : counts_) codes_[slot] = PrefixCode::from_counts(counts);
  }
  // The tables as SplitCodec serializes its own (PrefixCode::serialize), all of them.
  uint64_t table_bits() const {
    BitWriter w;
    for (const auto& [slot, code] : codes_) code.serialize(w);
    return w.size();
  }
  uint64_t bits(std::span<const uint32_t> nodes) const {
    uint64_t total = 0;
    for (uint32_t s : nodes)
      emit(s, [&](uint32_t slot, uint32_t sym, uint32_t raw) { total += codes_.at(slot).cost(sym) + raw; });
    return total;
  }

 private:
  void count(uint32_t slot, uint32_t sym) {
    auto& c = counts_[slot];
    if (c.size() <= sym) c.resize(sym + 1);
    ++c[sym];
  }
  template <class Out>
  void emit(uint32_t s, Out out) const {
    const uint32_t height = std::min<uint32_t>(uint32_t(std::max(0, max_depth_ - model_.id(s).depth())), 11);
    const uint32_t t = model_.first_child[s];
    const RefineInfo& ps = nested_.info[s];
    const bool refines[2] = {!never_refines(nested_.info[t]), !never_refines(nested_.info[t + 1])};
    out(0 + height, (refines[0] ? 0 : 1) | (refines[1] ? 0 : 2), 0);
    const Lattice e = escapes(v_);
    const uint32_t wide = e.angle + 2;
    uint32_t t_radius = 12;
    for (uint32_t k = 0; k < 2; ++k) {
      if (!refines[k]) continue;
      const ChildSymbols& c = nested_.symbols[t + k];
      const RefineInfo& info = nested_.info[t + k];
      out(100 + k * 100 + (k == 0 ? height : 50 + std::min(t_radius, 12u)), c.radius, c.radius > e.radius ? 11 : 0);
      if (k == 0) t_radius = c.radius;
      out(1000 + k * 100 + c.radius, c.mu, c.mu > e.mu ? 11 : 0);
      out(2000 + k * 100 + c.mu, c.delta, c.delta > e.delta ? 11 : 0);
      // Angle and axis choice in one symbol: inherited-axis entries, own-axis entries, no cone.
      const uint32_t angle_sym = c.no_cone ? 2 * wide : (c.own_axis ? wide : 0) + c.angle;
      const bool parent_cone = ps.cone_angle != kNoCone;
      out(3000 + k * 1000 + (parent_cone ? 1 + std::min(c.delta, 15u) : 0), angle_sym,
          !c.no_cone && c.angle > e.angle ? 10 : 0);
      if (c.no_cone || !c.own_axis) continue;
      const uint32_t room =
          parent_cone ? 1 + std::min<uint32_t>(
                                std::bit_width(uint32_t(std::max(0, int(ps.cone_angle) - int(info.cone_angle)))), 11)
                      : 0;
      for (const auto& [a, b] : {std::pair{info.cone_x, ps.cone_x}, {info.cone_y, ps.cone_y}}) {
        // An own axis is a multiple of the coarse step: coded in steps from the parent's, rounded down.
        const int64_t step = int64_t(1) << (c.absolute ? 0 : v_.axis_drop), from = parent_cone ? int16_t(b) : 0;
        const int64_t d =
            int64_t(std::floor(double(int16_t(a)) / double(step))) - int64_t(std::floor(double(from) / double(step)));
        const uint32_t width = d == 0 ? 0 : uint32_t(std::bit_width(uint64_t(std::abs(d))));
        out(6000 + k * 100 + room, d == 0 ? 0 : 2 * width - 1 + (d < 0), width > 0 ? width - 1 : 0);
      }
    }
  }

  const ModelData& model_;
  const Nested& nested_;
  const Variant& v_;
  int max_depth_ = 0;
  std::map<uint32_t, std::vector<uint64_t>> counts_;
  std::map<uint32_t, PrefixCode> codes_;
};

// Faces at tau = 1 px at issue 18's camera at distance d.
size_t faces(const ModelData& model, float d) {
  return refine_for_view(model, srmesh_camera(model, d, 0), 1).mesh.indices.size() / 3;
}

// The model's info as stored, coded by SplitCodec: E5's close view and the whole model; bunny's faces at
// issue 18's cameras too.
void report_stored(const std::string& name, const ModelData& model) {
  const std::vector<uint32_t> q = grid_positions(model, kBits);
  const std::vector<uint32_t> close = splits_for_view(model, close_view(model), 1.0f);
  const SplitCodec codec = SplitCodec::build(model, q, kBits);
  const RecordBitsReport view = record_bits(model, codec, q, close),
                         whole = record_bits(model, codec, q, model.split_order);
  std::printf(
      "%s as stored: close view %zu splits, info %.2f bits per split, topology + geometry %.2f; whole model info "
      "%.2f, topology + geometry %.2f\n",
      name.c_str(), close.size(), view.per_split(view.bits.refinement),
      view.per_split(view.bits.topology + view.bits.geometry), whole.per_split(whole.bits.refinement),
      whole.per_split(whole.bits.topology + whole.bits.geometry));
  if (name.starts_with("bunny"))
    for (float d : {1.5f, 3.f, 10.f, 50.f}) std::printf("  d %.1f: %zu faces\n", d, faces(model, d));
}

// Each variant nested over the model's own (unnested) info.
void measure(const char* name, const ModelData& model) {
  const std::vector<uint32_t> q = grid_positions(model, kBits);
  const Camera camera = close_view(model);
  const bool bunny = std::string(name) == "bunny";
  const std::vector<uint32_t> before = splits_for_view(model, camera, 1.0f);
  report_stored(std::string(name) + " (own bounds: this codec sends them exact)", model);
  const Variant variants[] = {
      {"r 2, mu 2, delta 2, angle 2, own axes", {2, 2, 2, 2}, -1, true, 0},
      {"r 2, mu 2, delta 2, angle 2, inherit at 1 step", {2, 2, 2, 2}, 1, true, 0},
      {"r 2, mu 64, delta 64, angle 64, own axes", {2, 64, 64, 64}, -1, true, 0},
      {"r 64, mu 2, delta 64, angle 64, own axes", {64, 2, 64, 64}, -1, true, 0},
      {"r 64, mu 64, delta 2, angle 64, own axes", {64, 64, 2, 64}, -1, true, 0},
      {"r 64, mu 64, delta 64, angle 2, own axes", {64, 64, 64, 2}, -1, true, 0},
      {"r 64, mu 64, delta 64, angle 64, own axes", {64, 64, 64, 64}, -1, true, 0},
      {"r 2, mu 16, delta 16, angle 8, own axes", {2, 16, 16, 8}, -1, true, 0},
      {"r 2, mu 64, delta 16, angle 8, own axes / 4", {2, 64, 16, 8}, -1, true, 2},
      {"r 2, mu 32, delta 16, angle 8, own axes / 4", {2, 32, 16, 8}, -1, true, 2},
      {"r 2, mu 64, delta 16, angle 8, own axes / 8", {2, 64, 16, 8}, -1, true, 3},
      {"r 2, mu 64, delta 16, angle 8, own axes / 8, v_t's radius below r(v_s)", {2, 64, 16, 8}, -1, false, 3},
      {"r 2, mu 64, delta 8, angle 4, own axes / 8", {2, 64, 8, 4}, -1, true, 3},
      {"r 2, mu 16, delta 16, angle 8, own axes / 8", {2, 16, 16, 8}, -1, true, 3},
      {"r 2, mu 16, delta 16, angle 8, inherit at 1 step, own axes / 8", {2, 16, 16, 8}, 1, true, 3},
  };

  for (const Variant& v : variants) {
    const Nested nested = nest(model, q, v);
    ModelData nested_model = model;
    nested_model.refine = nested.info;
    for (uint32_t n = 0; n < model.node_count(); ++n) {  // every bound still holds the node's own
      const RefineInfo& a = model.refine[n];
      const RefineInfo& b = nested.info[n];
      ASSERT_GE(rel(b.radius), rel(a.radius));
      ASSERT_GE(rel(b.mu), rel(a.mu));
      ASSERT_GE(rel(b.delta), rel(a.delta));
      ASSERT_GE(b.cone_angle, a.cone_angle);
      if (n >= model.root_count && !never_refines(a)) {
        const RefineInfo& p = nested.info[model.parent[n]];
        if (!never_refines(p) && nested.symbols[n].mu < escapes(v).mu) {
          ASSERT_LE(b.mu, p.mu);
        }
      }
    }
    const std::vector<uint32_t> close = splits_for_view(nested_model, camera, 1.0f);
    const InfoBits info(nested_model, nested, v);
    const SplitCodec codec = SplitCodec::build(nested_model, q, kBits);
    const RecordBitsReport view = record_bits(nested_model, codec, q, close);
    const RecordBitsReport whole = record_bits(nested_model, codec, q, model.split_order);
    std::printf(
        "%s, %s: %.1f %% inherit, %.2f exact values per child; close view %zu splits (%+.2f %%), info %.2f bits per "
        "split, topology + geometry %.2f; whole model info %.2f (tables %.1f KB), topology + geometry %.2f\n",
        name, v.name, 100.0 * double(nested.inherited) / double(nested.children),
        double(nested.escapes) / double(nested.children), close.size(),
        100.0 * (double(close.size()) / double(before.size()) - 1), view.per_split(info.bits(close)),
        view.per_split(view.bits.topology + view.bits.geometry), whole.per_split(info.bits(model.split_order)),
        double(info.table_bits()) / 8192, whole.per_split(whole.bits.topology + whole.bits.geometry));
    if (bunny)
      for (float d : {1.5f, 3.f, 10.f, 50.f}) std::printf("  d %.1f: %zu faces\n", d, faces(nested_model, d));
  }
}

// The variants start from each node's own bounds: bunny built without nesting (a file given in the
// environment should be one built with `pmstream build --unnested-info`).
TEST(RefineInfoNesting, CloseViewSplitsAgainstRefinementBits) {
  BuildOptions unnested;
  unnested.nested_info = false;
  PMS_MEASURE_RECORD_BITS_MODEL_BUILT(measure, unnested);
}

// What the builder stores (builder/nested_refine_info.h), coded by the real codec.
TEST(RefineInfoNesting, AsTheBuilderNestsIt) { PMS_MEASURE_RECORD_BITS_MODEL(report_stored); }

}  // namespace
}  // namespace pms::bench
