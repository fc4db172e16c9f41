// The body of a receiver-driven answer: the split records of the ids asked for and their descendants. One
// class, so the record format can change without the HTTP code (docs/protocol.md, "Receiver-driven over
// HTTP"). A model's format (ServedModel::records_format) is part of every ETag: 4, the compact records'
// bands (protocol/split_bands.h).
#pragma once
#include <cstdint>
#include <span>
#include <vector>

#include "common/bit_stream.h"
#include "protocol/split_request.h"
#include "server/catalogue.h"
#include "server/http_routes.h"

namespace pms::server {

// Writes the bands of the request's ids in order, a few ids between looks at the clock: an answer of
// thousands of ids is built over several turns of its connection.
class SplitRecordsWriter final : public BodyBuilder {
 public:
  // `nodes` are the request's nodes as split_lookup.h lists them (they size the answer). The model
  // outlives the writer (the catalogue holds it for the server's life).
  // With `phases`, building counts as search_splits.
  SplitRecordsWriter(const ServedModel& model, protocol::SplitRequest request, std::span<const uint32_t> nodes,
                     RecordForm form = RecordForm::info, PhaseTimes* phases = nullptr);

  bool build(std::chrono::steady_clock::time_point until) override;
  std::vector<uint8_t> take() override { return std::move(writer_).take(); }

 private:
  const ServedModel& model_;
  const protocol::StoredRecords& records_;
  protocol::SplitRequest request_;
  PhaseTimes* phases_;
  size_t next_id_ = 0;
  BitWriter writer_;
};

// The whole body in one go.
std::vector<uint8_t> split_records_body(const ServedModel& model, const protocol::SplitRequest& request,
                                        std::span<const uint32_t> nodes, RecordForm form = RecordForm::info);

}  // namespace pms::server
