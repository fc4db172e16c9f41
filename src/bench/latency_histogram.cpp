#include "bench/latency_histogram.h"

#include <algorithm>
#include <cmath>

#include "common/error.h"

namespace pms::bench {
namespace {

constexpr double kFloorMs = 0.001;  // everything under a microsecond shares bucket 0
constexpr double kGrowth = 1.02;

double upper_edge(int32_t index) { return kFloorMs * std::pow(kGrowth, double(index)); }

}  // namespace

void LatencyHistogram::add(double ms) {
  const int32_t index = ms <= kFloorMs ? 0 : int32_t(std::ceil(std::log(ms / kFloorMs) / std::log(kGrowth)));
  ++buckets_[index];
  ++count_;
  max_ms_ = std::max(max_ms_, ms);
}

void LatencyHistogram::merge(const LatencyHistogram& other) {
  for (const auto& [index, n] : other.buckets_) buckets_[index] += n;
  count_ += other.count_;
  max_ms_ = std::max(max_ms_, other.max_ms_);
}

double LatencyHistogram::percentile(double q) const {
  if (count_ == 0) return 0;
  // The nearest rank: the smallest sample with at least q of them at or below it.
  const uint64_t rank = std::max<uint64_t>(1, uint64_t(std::ceil(q * double(count_))));
  uint64_t seen = 0;
  for (const auto& [index, n] : buckets_)
    if ((seen += n) >= rank) return std::min(upper_edge(index), max_ms_);
  return max_ms_;
}

nlohmann::json LatencyHistogram::to_json() const {
  nlohmann::json buckets = nlohmann::json::array();
  for (const auto& [index, n] : buckets_) buckets.push_back({index, n});
  return {{"count", count_}, {"max_ms", max_ms_}, {"buckets", buckets}};
}

LatencyHistogram LatencyHistogram::from_json(const nlohmann::json& j) {
  LatencyHistogram h;
  if (!j.is_object() || !j.contains("buckets") || !j["buckets"].is_array() ||
      !j.contains("max_ms") || !j["max_ms"].is_number() || !j.contains("count") || !j["count"].is_number_unsigned())
    fail("latency histogram", "not one: " + j.dump());
  for (const nlohmann::json& b : j["buckets"]) {
    if (!b.is_array() || b.size() != 2 || !b[0].is_number_integer() || !b[1].is_number_unsigned())
      fail("latency histogram", "a bucket that is not [index, count]: " + b.dump());
    h.buckets_[b[0].get<int32_t>()] += b[1].get<uint64_t>();
    h.count_ += b[1].get<uint64_t>();
  }
  h.max_ms_ = j["max_ms"].get<double>();
  if (h.count_ != j["count"].get<uint64_t>()) fail("latency histogram", "its count is not its buckets' sum");
  return h;
}

}  // namespace pms::bench
