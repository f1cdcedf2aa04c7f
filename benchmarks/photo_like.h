#pragma once
/*
  Private to the benchmarks: the last steps that make a rendered frame photo-like (bench_klt,
  bench_two_planes): a camera's response curve (gamma 2.2 on linear light) and a JPEG round trip at
  quality 85. One place, so that both benchmarks' images are finished the same way.
*/
#include <vector>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

namespace yawdepth::bench {

/* An 8-bit gray photo-like frame from linear light (32-bit float, gray levels 0..255). */
inline cv::Mat photoFinish(const cv::Mat &linear_light)
{
  cv::Mat linear = cv::max(linear_light, 0.0) / 255.0, curved, out;
  cv::pow(linear, 1.0 / 2.2, curved);
  curved.convertTo(out, CV_8U, 255.0);
  std::vector<unsigned char> jpeg;
  cv::imencode(".jpg", out, jpeg, {cv::IMWRITE_JPEG_QUALITY, 85});
  return cv::imdecode(jpeg, cv::IMREAD_GRAYSCALE);
}

} // namespace yawdepth::bench
