// LatencyHistogram: percentiles within its 2 % buckets, merged across reports, and through JSON unchanged.
#include <gtest/gtest.h>

#include "bench/latency_histogram.h"
#include "common/error.h"

namespace pms::bench {
namespace {

TEST(LatencyHistogram, PercentilesWithinABucketOfTheSamples) {
  LatencyHistogram h;
  for (int i = 1; i <= 1000; ++i) h.add(0.1 * i);  // 0.1 .. 100 ms
  EXPECT_EQ(h.count(), 1000u);
  EXPECT_NEAR(h.percentile(0.5), 50.0, 50.0 * 0.021);
  EXPECT_NEAR(h.percentile(0.99), 99.0, 99.0 * 0.021);
  EXPECT_GE(h.percentile(0.99), 99.0);  // the bucket's upper edge: never below the sample
  EXPECT_DOUBLE_EQ(h.percentile(1), 100.0);
  EXPECT_EQ(LatencyHistogram().percentile(0.5), 0);
}

TEST(LatencyHistogram, MergedAndThroughJsonAsOne) {
  LatencyHistogram a, b, both;
  for (int i = 0; i < 100; ++i) {
    a.add(1 + i);
    b.add(200 + i);
    both.add(1 + i);
    both.add(200 + i);
  }
  LatencyHistogram merged = LatencyHistogram::from_json(a.to_json());
  merged.merge(LatencyHistogram::from_json(b.to_json()));
  EXPECT_EQ(merged.count(), both.count());
  EXPECT_EQ(merged.to_json(), both.to_json());
  for (double q : {0.1, 0.5, 0.9, 0.99}) EXPECT_EQ(merged.percentile(q), both.percentile(q));
  EXPECT_THROW(LatencyHistogram::from_json({{"count", 1}, {"max_ms", 1.0}, {"buckets", {{3, 2}}}}), Error);
  EXPECT_THROW(LatencyHistogram::from_json({{"buckets", "x"}}), Error);
}

}  // namespace
}  // namespace pms::bench
