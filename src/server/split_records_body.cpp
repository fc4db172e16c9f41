#include "server/split_records_body.h"

#include "common/bit_stream.h"
#include "protocol/split_bands.h"

namespace pms::server {

std::vector<uint8_t> split_records_body(const ServedModel& model, const protocol::SplitRequest& request,
                                        std::span<const uint32_t> nodes) {
  BitWriter w;
  uint64_t bits = 0;  // the records and at most two presence bits each
  for (uint32_t node : nodes)
    bits += model.tables->records().records.offsets[node + 1] - model.tables->records().records.offsets[node] + 2;
  w.reserve(bits);
  for (VertexId id : request.ids)
    protocol::write_split_band(model.model(), model.tables->records().records, model.model().find(id), request.depth,
                               w);
  return std::move(w).take();
}

}  // namespace pms::server
