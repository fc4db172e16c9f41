// What an HTTP request costs the server, in the work units of the per-address and per-connection budgets
// (work_budget.h): one unit is about the work of copying one split record into an answer, and the rest is
// counted in the same coin, so that a budget means the same CPU whatever a client asks for.
#pragma once
#include <cstddef>
#include <cstdint>

namespace pms::server {

// Parsing, routing, the headers and the system calls of a small request and its answer.
constexpr double kUnitsPerRequest = 32;
// Copying the answer's bytes (built or shared) to the socket, and reading the request's.
constexpr double kBytesPerUnit = 64;

inline double request_cost(uint64_t splits_encoded, size_t answer_bytes, size_t request_bytes) {
  return kUnitsPerRequest + double(splits_encoded) + double(answer_bytes + request_bytes) / kBytesPerUnit;
}

}  // namespace pms::server
