// The URLs the HTTP attackers aim at, from the model's own hierarchy: the most expensive split request
// the server's limits allow, and a resource whose pipelined answers fit the server's send buffer.
#pragma once
#include <cstdint>
#include <filesystem>
#include <string>

#include "bench/http_attack_run.h"

#include "spm/hierarchy.h"

namespace pms::bench {

struct ExpensiveRequest {
  std::string target;  // GET /models/{m}/{version}/splits/{code}
  uint32_t ids = 0, depth = 0;
  uint64_t splits = 0;  // split records in its answer
};

// At least 1,024 ids of one level of the hierarchy (as many as the URL limit takes, up to `max_ids`), with
// the deepest descendant depth (up to `max_depth`) whose answer stays within `max_splits` records.
// pms::Error when the model has no level of 1,024 internal nodes. `prefix` is the model's path, /models/{m}/{version}.
ExpensiveRequest most_expensive_request(const ModelData& model, const std::string& prefix, uint32_t max_ids = 4096,
                                        uint32_t max_depth = 8, uint64_t max_splits = 65536,
                                        size_t max_url_bytes = 4096);

// `pmstream build terrain:FACES` into DIR/terrain.pms (the model "terrain"); pms::Error when it fails.
std::string build_terrain(const std::string& pmstream_exe, const std::filesystem::path& dir, uint64_t faces);

// The attacks on the model of `pms` (named by the file's stem): an orbit of `frames` frames for the good
// client at 800 x 600 and `tolerance` pixels, and the most expensive request of the default limits.
AttackSetup attack_setup(const std::string& pmstream_exe, const std::string& pms, uint32_t frames, float tolerance);

}  // namespace pms::bench
