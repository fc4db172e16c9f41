// Latencies counted in logarithmic buckets 2 % wide, so several load processes can each report theirs on
// one JSON line and the bench merges them into percentiles (within 2 %) without shipping every sample.
#pragma once
#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>

namespace pms::bench {

class LatencyHistogram {
 public:
  void add(double ms);
  void merge(const LatencyHistogram& other);
  uint64_t count() const { return count_; }
  double max_ms() const { return max_ms_; }
  // The upper edge of the bucket holding the q-quantile (0 when empty).
  double percentile(double q) const;

  // {"count": N, "max_ms": M, "buckets": [[index, count], ...]}; from_json throws pms::Error on anything else.
  nlohmann::json to_json() const;
  static LatencyHistogram from_json(const nlohmann::json& j);

 private:
  std::map<int32_t, uint64_t> buckets_;  // index -> samples; bucket i holds (kFloor·g^(i-1), kFloor·g^i]
  uint64_t count_ = 0;
  double max_ms_ = 0;
};

}  // namespace pms::bench
