#pragma once
/// @file The obvious OpenCV implementation of the board segmentation, as a reference for tests
/// and benchmarks: cvtColor to HSV, one inRange per board (two for a hue window that wraps through
/// 0), countNonZero. Host and tests only; the firmware does not use it.

#include <cstdint>

#include <opencv2/core.hpp>

#include "harmoloc/algorithms/segmentation.hpp"

namespace harmoloc::reference {

/// Scratch images reused across frames (a benchmark must not time their allocation).
struct OpencvScratch {
  cv::Mat rgb;
  cv::Mat hsv;
  cv::Mat mask;
  cv::Mat mask2;
};

/// Areas of an RGB24 frame the OpenCV way. H bounds are ceil(min/2)..floor(max/2) on OpenCV's
/// 0..179 scale, as BoardClassifier documents.
void opencv_segment_rgb24(const std::uint8_t* data, int width_px, int height_px, int stride_bytes,
                          const algorithms::ThresholdSet& thresholds, algorithms::AreaVector& areas,
                          OpencvScratch& scratch);

/// Areas of a YUYV frame the OpenCV way: cvtColor(COLOR_YUV2RGB_YUYV) first.
void opencv_segment_yuyv(const std::uint8_t* data, int width_px, int height_px, int stride_bytes,
                         const algorithms::ThresholdSet& thresholds, algorithms::AreaVector& areas,
                         OpencvScratch& scratch);

}  // namespace harmoloc::reference
