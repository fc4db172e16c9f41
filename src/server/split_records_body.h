// The body of a receiver-driven answer: the split records of the ids asked for and their descendants. One
// function, so the record format can change without the HTTP code (docs/protocol.md, "Receiver-driven over
// HTTP"). A model's format (ServedModel::records_format) is part of every ETag: 4, the compact records'
// bands (protocol/split_bands.h).
#pragma once
#include <cstdint>
#include <span>
#include <vector>

#include "protocol/split_request.h"
#include "server/catalogue.h"

namespace pms::server {

// `nodes` are the request's nodes as split_lookup.h lists them (they size the answer).
std::vector<uint8_t> split_records_body(const ServedModel& model, const protocol::SplitRequest& request,
                                        std::span<const uint32_t> nodes);

}  // namespace pms::server
