// Split records on the bunny as the bench measures them: bits per split by part over the whole split order
// and over E5's close view, beside today's VSPLITS refinement bits for the same splits. With
// PMSTREAM_RECORD_BITS_PMS=FILE.pms (e.g. a dragon from `pmstream build`) the same numbers for that file.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>

#include "bench/split_record_bits.h"
#include "builder/build.h"
#include "io/mesh.h"
#include "spm/hierarchy.h"
#include "spm/pms_file.h"
#include "spm/split_codec.h"
#include "test_support.h"

namespace pms::bench {
namespace {

constexpr uint32_t kBits = 16;

void print(const char* what, const RecordBitsReport& r) {
  std::printf(
      "%s: %zu splits, bits per split: topology %.2f, geometry %.2f, refinement %.2f, normal + color %.2f, "
      "total %.2f (VSPLITS refinement today %.2f); tables %.1f KB\n",
      what, r.splits, r.per_split(r.bits.topology), r.per_split(r.bits.geometry), r.per_split(r.bits.refinement),
      r.per_split(r.bits.attributes()), r.per_split(r.bits.total()), r.per_split(r.packet_refinement),
      double(r.table_bits) / 8192);
}

// Whole split order and E5's close view; returns the close view's report.
RecordBitsReport measure(const char* name, const ModelData& model) {
  const std::vector<uint32_t> q = grid_positions(model, kBits);
  const SplitCodec codec = SplitCodec::build(model, q, kBits);
  const RecordBitsReport whole = record_bits(model, codec, q, model.split_order);
  print((std::string(name) + " whole model").c_str(), whole);
  EXPECT_EQ(whole.splits, model.split_order.size());
  EXPECT_LT(whole.bits.refinement, whole.packet_refinement);
  const std::vector<uint32_t> close = splits_for_view(model, close_view(model), 1.0f);
  const RecordBitsReport view = record_bits(model, codec, q, close);
  print((std::string(name) + " E5 close view, tau 1 px").c_str(), view);
  return view;
}

TEST(SplitRecordBits, BunnyWholeModelAndCloseView) {
  PMS_REQUIRE_SHARED_MODEL(path, "bunny.ply.xz");
  Mesh mesh = load_mesh(path.string());
  clean_mesh(mesh);
  const Hierarchy h = build_progressive_mesh(mesh).hierarchy;
  const RecordBitsReport view = measure("bunny", model_of(h));
  EXPECT_GT(view.splits, 1000u);  // the close view refines a good part of the model
  EXPECT_LT(view.bits.refinement, view.packet_refinement);
}

TEST(SplitRecordBits, FileGivenInTheEnvironment) {
  const char* path = std::getenv("PMSTREAM_RECORD_BITS_PMS");
  if (!path) GTEST_SKIP() << "set PMSTREAM_RECORD_BITS_PMS=FILE.pms to measure that model";
  const auto file = PmsFile::open(path);
  measure(path, file->model());
}

}  // namespace
}  // namespace pms::bench
