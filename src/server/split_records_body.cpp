#include "server/split_records_body.h"

#include "protocol/split_bands.h"

namespace pms::server {
namespace {

// Ids written between looks at the clock: a band of a deep request is thousands of records, a shallow
// one a few, and reading the clock costs about as much as a shallow band.
constexpr size_t kIdsPerLook = 16;

}  // namespace

SplitRecordsWriter::SplitRecordsWriter(const ServedModel& model, protocol::SplitRequest request,
                                       std::span<const uint32_t> nodes, RecordForm form, PhaseTimes* phases)
    : model_(model), records_(model.tables->records(form).records), request_(std::move(request)), phases_(phases) {
  const PhaseTimer timer(phases_, Phase::search_splits);
  const auto& offsets = records_.offsets;
  uint64_t bits = 0;  // the records and at most two presence bits each
  for (uint32_t node : nodes) bits += offsets[node + 1] - offsets[node] + 2;
  writer_.reserve(bits);
}

bool SplitRecordsWriter::build(std::chrono::steady_clock::time_point until) {
  const PhaseTimer timer(phases_, Phase::search_splits);
  while (next_id_ < request_.ids.size()) {
    const size_t end = std::min(request_.ids.size(), next_id_ + kIdsPerLook);
    for (; next_id_ < end; ++next_id_)
      protocol::write_split_band(model_.model(), records_, model_.model().find(request_.ids[next_id_]), request_.depth,
                                 writer_);
    if (next_id_ < request_.ids.size() && std::chrono::steady_clock::now() >= until) return false;
  }
  return true;
}

std::vector<uint8_t> split_records_body(const ServedModel& model, const protocol::SplitRequest& request,
                                        std::span<const uint32_t> nodes, RecordForm form) {
  SplitRecordsWriter writer(model, request, nodes, form);
  writer.build(std::chrono::steady_clock::time_point::max());
  return writer.take();
}

}  // namespace pms::server
