#include "harmoloc/firmware/latency_window.hpp"

#include <gtest/gtest.h>

namespace hf = harmoloc::firmware;

TEST(LatencyWindow, EmptyPeriodReportsNothing) {
  hf::LatencyWindow w;
  EXPECT_EQ(w.take().count, 0U);
}

TEST(LatencyWindow, MedianAndMaximumOfThePeriodThenStartsAgain) {
  hf::LatencyWindow w;
  for (std::uint64_t v : {9U, 3U, 7U, 1U, 5U}) w.record(v);
  hf::LatencyWindow::Summary s = w.take();
  EXPECT_EQ(s.count, 5U);
  EXPECT_EQ(s.median_ns, 5U);
  EXPECT_EQ(s.max_ns, 9U);
  // Even count: the lower median, a value that was measured.
  for (std::uint64_t v : {40U, 10U, 30U, 20U}) w.record(v);
  s = w.take();
  EXPECT_EQ(s.count, 4U);
  EXPECT_EQ(s.median_ns, 20U);
  EXPECT_EQ(s.max_ns, 40U);  // the first period's 9 is gone
  EXPECT_EQ(w.take().count, 0U);
}

TEST(LatencyWindow, AnOverfullPeriodKeepsTheLatestForTheMedianAndEverySampleForTheMaximum) {
  hf::LatencyWindow w;
  w.record(1'000'000);  // an early outlier, pushed out of the ring
  for (std::size_t i = 0; i < hf::LatencyWindow::kCapacity; ++i) w.record(100 + i);
  const hf::LatencyWindow::Summary s = w.take();
  EXPECT_EQ(s.count, hf::LatencyWindow::kCapacity + 1);
  EXPECT_EQ(s.median_ns, 100 + (hf::LatencyWindow::kCapacity - 1) / 2);
  EXPECT_EQ(s.max_ns, 1'000'000U);
}
