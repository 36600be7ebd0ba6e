#include "opencv_reference.hpp"

#include <cmath>

#include <opencv2/imgproc.hpp>

namespace harmoloc::reference {

namespace {

void count_boards(const cv::Mat& hsv, const algorithms::ThresholdSet& thresholds,
                  algorithms::AreaVector& areas, OpencvScratch& s) {
  areas.pixels.fill(0U);
  areas.count = thresholds.count;
  for (std::size_t k = 0; k < thresholds.count; ++k) {
    const algorithms::ColourThreshold& t = thresholds.boards[k];
    const int lo = static_cast<int>(std::ceil(t.hue_min_deg / 2.0F));
    const int hi = static_cast<int>(std::floor(t.hue_max_deg / 2.0F));
    if (t.hue_min_deg <= t.hue_max_deg) {
      cv::inRange(hsv, cv::Scalar(lo, t.saturation_min, t.value_min),
                  cv::Scalar(hi, 255, t.value_max), s.mask);
    } else {
      cv::inRange(hsv, cv::Scalar(lo, t.saturation_min, t.value_min),
                  cv::Scalar(179, 255, t.value_max), s.mask);
      cv::inRange(hsv, cv::Scalar(0, t.saturation_min, t.value_min),
                  cv::Scalar(hi, 255, t.value_max), s.mask2);
      cv::bitwise_or(s.mask, s.mask2, s.mask);
    }
    areas.pixels[k] = static_cast<std::uint32_t>(cv::countNonZero(s.mask));
  }
}

}  // namespace

void opencv_segment_rgb24(const std::uint8_t* data, int width_px, int height_px, int stride_bytes,
                          const algorithms::ThresholdSet& thresholds, algorithms::AreaVector& areas,
                          OpencvScratch& scratch) {
  const cv::Mat rgb(height_px, width_px, CV_8UC3, const_cast<std::uint8_t*>(data),
                    static_cast<std::size_t>(stride_bytes));
  cv::cvtColor(rgb, scratch.hsv, cv::COLOR_RGB2HSV);
  count_boards(scratch.hsv, thresholds, areas, scratch);
}

void opencv_segment_yuyv(const std::uint8_t* data, int width_px, int height_px, int stride_bytes,
                         const algorithms::ThresholdSet& thresholds, algorithms::AreaVector& areas,
                         OpencvScratch& scratch) {
  const cv::Mat yuyv(height_px, width_px, CV_8UC2, const_cast<std::uint8_t*>(data),
                     static_cast<std::size_t>(stride_bytes));
  cv::cvtColor(yuyv, scratch.rgb, cv::COLOR_YUV2RGB_YUYV);
  cv::cvtColor(scratch.rgb, scratch.hsv, cv::COLOR_RGB2HSV);
  count_boards(scratch.hsv, thresholds, areas, scratch);
}

}  // namespace harmoloc::reference
