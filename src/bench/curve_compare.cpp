#include "bench/curve_compare.h"

#include <algorithm>

namespace pms::bench {

std::optional<uint64_t> bytes_to_reach(const std::vector<CurveSample>& samples, double psnr) {
  for (const CurveSample& s : samples)
    if (s.psnr >= psnr) return s.bytes;
  return std::nullopt;
}

std::optional<double> psnr_at(const std::vector<CurveSample>& samples, uint64_t bytes, double cap) {
  const auto after = std::upper_bound(samples.begin(), samples.end(), bytes,
                                      [](uint64_t b, const CurveSample& s) { return b < s.bytes; });
  if (after == samples.begin()) return std::nullopt;
  return std::min(std::prev(after)->psnr, cap);
}

CurveOrder compare_curves(const std::vector<CurveSample>& upper, const std::vector<CurveSample>& lower, double cap) {
  CurveOrder order;
  std::vector<uint64_t> counts;
  for (const auto* curve : {&upper, &lower})
    for (const CurveSample& s : *curve) counts.push_back(s.bytes);
  std::sort(counts.begin(), counts.end());
  counts.erase(std::unique(counts.begin(), counts.end()), counts.end());
  for (const uint64_t bytes : counts) {
    const std::optional<double> u = psnr_at(upper, bytes, cap), l = psnr_at(lower, bytes, cap);
    if (!u || !l) continue;
    ++order.compared;
    if (*u > *l) {
      ++order.above;
    } else if (*u == *l) {
      ++order.equal;
    } else {
      if (order.below++ == 0) order.first_below_bytes = bytes;
      order.worst_deficit = std::max(order.worst_deficit, *l - *u);
    }
  }
  return order;
}

}  // namespace pms::bench
