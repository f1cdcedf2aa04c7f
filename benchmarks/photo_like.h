#pragma once
/*
  Private to the benchmarks: what bench_klt and bench_two_planes share to render textured planes as
  photo-like frames: a fronto-parallel plane's homography between two pinhole cameras, and the last
  steps of a frame (a camera's response curve, gamma 2.2 on linear light, and a JPEG round trip at
  quality 85). One place, so that both benchmarks' images are made the same way.
*/
#include <vector>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <visp3/core/vpHomogeneousMatrix.h>

namespace yawdepth::bench {

/* The homography of the plane Z = depth (first camera's frame) from the first camera's pixels to
   those of the camera at `cMc0`, both with the pinhole (focal, u0, v0). */
inline cv::Matx33d planeHomography(const vpHomogeneousMatrix &cMc0, double depth, double focal, double u0, double v0)
{
  const cv::Matx33d K(focal, 0, u0, 0, focal, v0, 0, 0, 1);
  cv::Matx33d A;
  for (unsigned i = 0; i < 3; ++i)
    for (unsigned j = 0; j < 3; ++j)
      A(i, j) = cMc0[i][j] + (j == 2 ? cMc0[i][3] / depth : 0.0);
  return K * A * K.inv();
}

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
