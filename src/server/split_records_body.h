// The body of a receiver-driven answer: the split records of the nodes asked for, in order. One function,
// so the record format can change without the HTTP code (docs/protocol.md, "Receiver-driven over HTTP").
#pragma once
#include <cstdint>
#include <span>
#include <vector>

#include "server/catalogue.h"

namespace pms::server {

// Changes whenever the body's bytes for the same nodes change: it is part of every ETag.
constexpr uint32_t kSplitRecordsFormat = 1;  // a VSPLITS payload (frame 0, final) of the model's packets

// The records of `nodes` (internal nodes of the model), in that order.
std::vector<uint8_t> split_records_body(const ServedModel& model, std::span<const uint32_t> nodes);

}  // namespace pms::server
