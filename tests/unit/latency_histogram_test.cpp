// The log-linear latency histogram: bucket edges, quantile accuracy, exact extremes.
#include "harmoloc/firmware/latency_histogram.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

#include "harmoloc/algorithms/random.hpp"

namespace hf = harmoloc::firmware;
using Histogram = hf::LatencyHistogram;

namespace {

// Values 0..10^10 ns: every value up to 10^5, then a geometric sweep that also hits every power of
// two and its neighbours (the octave edges).
std::vector<std::uint64_t> sweep_values() {
  std::vector<std::uint64_t> v;
  for (std::uint64_t x = 0; x <= 100000; ++x) v.push_back(x);
  for (double x = 1e5; x <= 1e10; x *= 1.0007) v.push_back(static_cast<std::uint64_t>(x));
  for (int b = 6; b <= 34; ++b) {
    const std::uint64_t p = std::uint64_t{1} << b;
    v.insert(v.end(), {p - 1, p, p + 1});
  }
  v.push_back(10000000000ULL);
  return v;
}

}  // namespace

TEST(LatencyHistogram, BucketsAreContiguousHalfOpenRanges) {
  // Bucket i holds [bucket_upper_ns(i - 1), bucket_upper_ns(i)): the upper edge is the first value
  // of the next bucket, so a value is below its bucket's upper edge and at or above the previous.
  for (std::uint64_t v : sweep_values()) {
    const std::size_t b = Histogram::bucket_of(v);
    ASSERT_LT(b, Histogram::kBuckets) << v;
    ASSERT_LT(v, Histogram::bucket_upper_ns(b)) << "value " << v << " bucket " << b;
    if (b > 0) {
      ASSERT_GE(v, Histogram::bucket_upper_ns(b - 1)) << "value " << v << " bucket " << b;
    }
  }
  // Edges strictly increase and every edge starts the next bucket.
  for (std::size_t i = 1; i < Histogram::kBuckets; ++i) {
    ASSERT_GT(Histogram::bucket_upper_ns(i), Histogram::bucket_upper_ns(i - 1)) << i;
    ASSERT_EQ(Histogram::bucket_of(Histogram::bucket_upper_ns(i - 1)), i) << i;
  }
}

TEST(LatencyHistogram, BucketWidthIsWithinOneSixtyFourth) {
  for (std::size_t i = 1; i < Histogram::kBuckets; ++i) {
    const auto lo = static_cast<double>(Histogram::bucket_upper_ns(i - 1));
    const auto hi = static_cast<double>(Histogram::bucket_upper_ns(i));
    if (lo >= 64.0) {
      ASSERT_LE((hi - lo) / lo, 1.0 / 64.0 + 1e-12) << i;
    } else {
      ASSERT_EQ(hi - lo, 1.0) << i;  // exact below 64 ns
    }
  }
}

TEST(LatencyHistogram, QuantilesWithinOnePointSixPercentOfExact) {
  auto h = std::make_unique<Histogram>();
  harmoloc::algorithms::Pcg32 rng(2024);
  std::vector<std::uint64_t> values;
  // Log-uniform from 1 us to 1 s, as stage and cycle times spread.
  for (int i = 0; i < 100000; ++i) {
    const auto v = static_cast<std::uint64_t>(std::exp(rng.uniform(std::log(1e3), std::log(1e9))));
    values.push_back(v);
    h->record(v);
  }
  std::sort(values.begin(), values.end());
  for (double q : {0.0, 0.001, 0.01, 0.1, 0.25, 0.5, 0.75, 0.9, 0.99, 0.999, 0.9999}) {
    const std::size_t rank = std::max<std::size_t>(
        1, static_cast<std::size_t>(std::ceil(q * static_cast<double>(values.size()))));
    const auto exact = static_cast<double>(values[rank - 1]);
    const auto got = static_cast<double>(h->quantile_ns(q));
    EXPECT_LE(std::fabs(got - exact) / exact, 0.016)
        << "q " << q << " exact " << exact << " got " << got;
    EXPECT_GE(got, exact) << "q " << q;  // an upper edge never under-reports
  }
  EXPECT_EQ(h->quantile_ns(1.0), values.back());
  EXPECT_EQ(h->max_ns(), values.back());
  EXPECT_EQ(h->min_ns(), values.front());
  EXPECT_EQ(h->count(), values.size());
  long double sum = 0;
  for (std::uint64_t v : values) sum += static_cast<long double>(v);
  EXPECT_NEAR(h->mean_ns(), static_cast<double>(sum / static_cast<long double>(values.size())),
              1e-6 * h->mean_ns());
  std::uint64_t in_buckets = 0;
  for (std::size_t i = 0; i < Histogram::kBuckets; ++i) in_buckets += h->bucket_count(i);
  EXPECT_EQ(in_buckets, values.size());
}

TEST(LatencyHistogram, EmptyAndSingleValue) {
  auto h = std::make_unique<Histogram>();
  EXPECT_EQ(h->count(), 0U);
  EXPECT_EQ(h->quantile_ns(0.5), 0U);
  EXPECT_EQ(h->max_ns(), 0U);
  EXPECT_EQ(h->min_ns(), 0U);
  EXPECT_EQ(h->mean_ns(), 0.0);
  h->record(12345678);
  for (double q : {0.0, 0.5, 0.99, 1.0})
    EXPECT_EQ(h->quantile_ns(q), 12345678U) << q;  // capped by the max
  EXPECT_EQ(h->min_ns(), 12345678U);
  EXPECT_DOUBLE_EQ(h->mean_ns(), 12345678.0);
}

TEST(LatencyHistogram, MaxIsExactForHugeValues) {
  auto h = std::make_unique<Histogram>();
  h->record(5);
  h->record(UINT64_MAX / 4);
  EXPECT_EQ(h->max_ns(), UINT64_MAX / 4);
  EXPECT_EQ(h->quantile_ns(1.0), UINT64_MAX / 4);
  EXPECT_EQ(Histogram::bucket_of(UINT64_MAX), Histogram::kBuckets - 1);
}

TEST(LatencyHistogram, RangeCoversOverAnHourAsDocumented) {
  // The header promises buckets "up to 2^(36+6) ns (over an hour)": a one-hour stall must be
  // reported as one hour (within the 1.6%), not clipped at the top bucket's edge.
  const std::uint64_t hour_ns = 3600ULL * 1000000000ULL;
  auto h = std::make_unique<Histogram>();
  for (int i = 0; i < 3; ++i) h->record(hour_ns);
  h->record(hour_ns + 1000);
  const auto got = static_cast<double>(h->quantile_ns(0.5));
  EXPECT_LE(std::fabs(got - static_cast<double>(hour_ns)) / static_cast<double>(hour_ns), 0.016)
      << "p50 of one-hour values reported as " << got * 1e-9 << " s; top bucket edge "
      << static_cast<double>(Histogram::bucket_upper_ns(Histogram::kBuckets - 1)) * 1e-9 << " s";
}
