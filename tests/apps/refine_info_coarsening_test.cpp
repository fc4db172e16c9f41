// What coarser RefineInfo quantization would cost and save (issue 19, the close view's refinement info): every
// node's bounds rounded up to fewer length mantissa bits and cone-angle steps (so each still covers what it
// covered), then E5's close view refined again at tau = 1 px. Reports the splits (about 2 faces each) that
// view takes and the records' refinement bits with a coder that drops the always-zero low bits. The axis is
// kept: delta is measured along it, so moving it would need mu and delta re-measured in the builder.
// PMSTREAM_RECORD_BITS_PMS=FILE.pms measures that file, else the bunny.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <vector>

#include "apps/bench/split_record_bits.h"
#include "builder/build.h"
#include "io/mesh.h"
#include "pm/hierarchy.h"
#include "pm/pms_file.h"
#include "pm/split_codec.h"
#include "record_bits_model.h"
#include "test_support.h"

namespace pms::app {
namespace {

// Rounds a length's half float up to `extra` fewer mantissa bits (monotone bits: a carry bumps the exponent).
uint16_t coarser_length(uint16_t half, unsigned extra) {
  const uint32_t mask = (1u << (kLengthDroppedBits + extra)) - 1;
  return uint16_t(std::min<uint32_t>((uint32_t(half) + mask) & ~mask, 0x7C00));
}

RefineInfo coarser(RefineInfo info, unsigned length_extra, unsigned angle_extra) {
  if (never_refines(info)) return info;
  for (uint16_t RefineInfo::*f : {&RefineInfo::radius, &RefineInfo::mu, &RefineInfo::delta}) info.*f = coarser_length(info.*f, length_extra);
  if (info.cone_angle != kNoCone) {
    const uint32_t mask = (1u << angle_extra) - 1;
    const uint32_t angle = (uint32_t(info.cone_angle) + mask) & ~mask;
    if (angle > kConeSteps) info.cone_angle = kNoCone, info.cone_x = info.cone_y = 0;
    else info.cone_angle = uint16_t(angle);
  }
  return info;
}

// Low bits the records' integers carry that a coder aware of the coarser steps would not: one per dropped
// bit for every nonzero difference (the codec's classes just shift), as split_codec.cpp codes them.
uint64_t zero_bits(const ModelData& model, std::span<const uint32_t> nodes, unsigned length_extra, unsigned angle_extra) {
  uint64_t bits = 0;
  for (uint32_t node : nodes) {
    const RefineInfo s = as_sent(model.refine[node]);
    for (uint32_t k = 0; k < 2; ++k) {
      const RefineInfo v = as_sent(model.refine[model.first_child[node] + k]);
      if (never_refines(v)) continue;
      for (uint16_t RefineInfo::*f : {&RefineInfo::radius, &RefineInfo::mu, &RefineInfo::delta})
        if ((s.*f >> kLengthDroppedBits) != (v.*f >> kLengthDroppedBits)) bits += length_extra;
      if (v.cone_angle == kNoCone) continue;
      const int64_t d = s.cone_angle != kNoCone ? int64_t(s.cone_angle) - v.cone_angle : int64_t(v.cone_angle);
      if (d != 0) bits += angle_extra;
    }
  }
  return bits;
}

void measure(const char* name, const ModelData& model) {
  const std::vector<uint32_t> q = grid_positions(model, 16);
  const Camera camera = close_view(model);
  size_t fine_splits = 0;
  for (const auto& [length_extra, angle_extra] : {std::pair{0u, 0u}, {1u, 0u}, {2u, 0u}, {3u, 0u}, {0u, 2u}, {0u, 4u}, {2u, 3u}, {3u, 4u}}) {
    std::vector<RefineInfo> refine(model.refine.begin(), model.refine.end());
    for (RefineInfo& info : refine) {
      const RefineInfo before = info;
      info = coarser(info, length_extra, angle_extra);
      const RefineBounds a = dequantize_refine(before, model.scale), b = dequantize_refine(info, model.scale);
      ASSERT_GE(b.radius, a.radius);
      ASSERT_GE(b.mu, a.mu);
      ASSERT_GE(b.delta, a.delta);
      ASSERT_GE(b.cone_angle, a.cone_angle);  // the same axis, a wider cone: covers what it covered
    }
    ModelData coarse = model;
    coarse.refine = refine;
    const std::vector<uint32_t> close = splits_for_view(coarse, camera, 1.0f);
    if (length_extra == 0 && angle_extra == 0) fine_splits = close.size();
    const SplitCodec codec = SplitCodec::build(coarse, q, 16);
    const RecordBitsReport view = record_bits(coarse, codec, q, close);
    const RecordBitsReport whole = record_bits(coarse, codec, q, coarse.split_order);
    const double view_info = view.per_split(view.bits.refinement - zero_bits(coarse, close, length_extra, angle_extra));
    const double whole_info = whole.per_split(whole.bits.refinement - zero_bits(coarse, coarse.split_order, length_extra, angle_extra));
    std::printf("%s: lengths -%u mantissa bits, angle /%u: close view %zu splits (%+.2f %%), refinement %.2f bits "
                "per split (geometry %.2f); whole model refinement %.2f\n",
                name, length_extra, 1u << angle_extra, close.size(), 100.0 * (double(close.size()) / double(fine_splits) - 1),
                view_info, view.per_split(view.bits.geometry), whole_info);
    EXPECT_GE(close.size() + close.size() / 100, fine_splits);  // coarser bounds never refine much less
  }
}

TEST(RefineInfoCoarsening, CloseViewSplitsAgainstRefinementBits) {
  PMS_MEASURE_RECORD_BITS_MODEL(measure);
}

}  // namespace
}  // namespace pms::app
