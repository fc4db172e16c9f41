// Split records (spm/split_codec.h) measured on a model at the wire's position grid: bits per split by part
// over the whole split order, or over the splits one view asks for (E5's close view).
#pragma once
#include <cstdint>
#include <span>
#include <vector>

#include "common/camera.h"
#include "spm/hierarchy.h"
#include "spm/split_codec.h"

namespace pms::bench {

struct RecordBitsReport {
  size_t splits = 0;
  RecordBits bits;                 // the records' bits by part, summed
  uint64_t packet_refinement = 0;  // the same splits' info_t + info_u in today's VSPLITS packets, summed
  uint64_t table_bits = 0;         // the model's code tables, serialized
  double per_split(uint64_t total) const { return splits ? double(total) / double(splits) : 0; }
};

// Encodes the records of `nodes` (internal nodes) with `codec` and sums their bits.
RecordBitsReport record_bits(const ModelData& model, const SplitCodec& codec, std::span<const uint32_t> positions,
                             std::span<const uint32_t> nodes);

// E5's close view: the first orbit camera moved halfway to its target (the model overflows the screen).
Camera close_view(const ModelData& model);

// The internal nodes local refinement splits for `camera` at `tolerance_px`, from the base mesh.
std::vector<uint32_t> splits_for_view(const ModelData& model, const Camera& camera, float tolerance_px);

}  // namespace pms::bench
