// The body of a receiver-driven answer in records format 3 (docs/protocol.md, "Receiver-driven over HTTP"):
// for each requested id, the compact split records (spm/split_codec.h) of its band — the id's split and its
// descendants' down to the request's depth — in one bit stream. Both ends walk the band the same way, so
// the stream needs no ids: a record's children are known from its id, and whether a child has a split of
// its own is implied by its refinement info unless that info never refines (then one bit says); in the plain
// form (RecordForm::plain) the record says it.
// Shared with the browser build: single-threaded, no std::ranges algorithms, std::format or coroutines.
#pragma once
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "common/bit_stream.h"
#include "protocol/split_request.h"
#include "spm/hierarchy.h"
#include "spm/position_grid.h"
#include "spm/split_codec.h"
#include "spm/split_record.h"
#include "spm/vertex_hierarchy.h"

namespace pms::protocol {

// The model's stored records (PmsFile::split_records() and split_offsets(), or encode_records()).
struct StoredRecords {
  std::span<const uint8_t> bits;
  std::span<const uint64_t> offsets;  // node i's record: bits [offsets[i], offsets[i + 1])
  // A plain record says itself which children have splits: its bands carry no presence bits.
  RecordForm form = RecordForm::info;
};

// Appends the band of internal node `root`, `depth` levels down, to `w`. Returns the records written.
uint32_t write_split_band(const ModelData& model, const StoredRecords& records, uint32_t root, uint32_t depth,
                          BitWriter& w);

// What a client holds about the split of `slot` (spm/split_codec.h, SplitContext), from its own hierarchy:
// the position re-quantized (the grid gives the sent integers back), the info as sent, the normal
// re-quantized and the color, the ancestors' cuts.
SplitContext held_split_context(const VertexHierarchy& h, uint32_t slot, const PositionGrid& grid);

// StreamContext::held for a client whose hierarchy is `h` (which must outlive the context): the context of
// every vertex it holds, by held_split_context.
std::function<bool(VertexId, SplitContext&)> held_in(const VertexHierarchy& h, const PositionGrid& grid);

// The split a decoded record describes, for VertexHierarchy::add_split: v_t's normal and color when the
// codec's records carry them.
SplitRecord split_record_of(VertexId vs, const SplitPayload& payload, const PositionGrid& grid,
                            const SplitCodec& codec);

// Reads an answer to `request` and adds every split it carries that `h` lacks (one it already holds is
// decoded and checked for its children, then skipped). Returns the splits added. Throws pms::Error for a
// body that is not one: an id the client does not hold, a record that does not decode, more than
// `max_splits` records, or bits left over past the final byte's padding.
uint32_t read_split_bands(std::span<const uint8_t> body, const SplitRequest& request, const SplitCodec& codec,
                          const PositionGrid& grid, VertexHierarchy& h, uint32_t max_splits);

}  // namespace pms::protocol
