#pragma once
/*
  klt_wall.h: bench_klt's photo-like sequence of a textured wall, shared by bench_klt and
  bench_tracker_errors (one owner). Header-only, not installed.

  Scene: a textured wall kWallDepth = 2 m in front of the first camera (smoothed uniform noise, seeded;
  each frame made photo-like: blur 0.8 px, vignetting 30 %, noise 2 gray levels, a gamma 2.2 response
  curve, JPEG at quality 85), the camera stepping 4 mm sideways per frame with a slow pan of +-1
  degree; each image is the first camera's texture warped by the wall's homography (cubic, the
  texture mirrored beyond its 640x480 border).
*/
#include <cmath>
#include <vector>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <visp3/core/vpHomogeneousMatrix.h>
#include <yawdepth/core/types.h>
#include <yawdepth/geometry/rig.h>

#include "photo_like.h"

namespace yawdepth::bench::wall {

constexpr double kFocal = 600, kU0 = 320, kV0 = 240, kWallDepth = 2.0;
constexpr int kWidth = 640, kHeight = 480;

/* The sequence: its motion rows and rendered images. */
struct Sequence {
  std::vector<MotionSample> motion;
  std::vector<cv::Mat> images;
};

/* The wall's homography from the first camera's pixels (the texture's) to the camera at `cMc0`'s. */
inline cv::Matx33d wallHomography(const vpHomogeneousMatrix &cMc0)
{
  return planeHomography(cMc0, kWallDepth, kFocal, kU0, kV0);
}

/* The first camera's pose in frame `k`'s camera (c_k M c_0). */
inline vpHomogeneousMatrix cMc0(const Sequence &s, std::size_t k)
{
  const YawRig rig;
  return wMc(rig, s.motion[k]).inverse() * wMc(rig, s.motion.front());
}

/* Renders `frames` frames (see the file); seeded, the same images on every call. */
inline Sequence renderSequence(int frames)
{
  cv::Mat noise(kHeight, kWidth, CV_32F), smooth;
  cv::RNG rng(11);
  rng.fill(noise, cv::RNG::UNIFORM, 0.0, 255.0);
  cv::GaussianBlur(noise, smooth, cv::Size(0, 0), 2.0);
  cv::normalize(smooth, smooth, 20, 235, cv::NORM_MINMAX);
  cv::Mat texture;
  smooth.convertTo(texture, CV_8U);
  Sequence s;
  // Vignetting: the light falls by 30 % towards the corners, quadratic in the radius.
  cv::Mat vignetting(kHeight, kWidth, CV_32F);
  for (int v = 0; v < kHeight; ++v)
    for (int u = 0; u < kWidth; ++u)
      vignetting.at<float>(v, u) =
          static_cast<float>(1.0 - 0.3 * ((u - kU0) * (u - kU0) + (v - kV0) * (v - kV0)) / (kU0 * kU0 + kV0 * kV0));
  for (int k = 0; k < frames; ++k) {
    MotionSample m;
    m.frame = k;
    m.x = 0.004 * k;
    m.heading = 0.0175 * std::sin(k / 8.0);
    s.motion.push_back(m);
    cv::Mat warped, blurred, frame_noise(kHeight, kWidth, CV_32F);
    cv::warpPerspective(texture, warped, cv::Mat(wallHomography(cMc0(s, s.motion.size() - 1))), texture.size(),
                        cv::INTER_CUBIC, cv::BORDER_REFLECT);
    cv::GaussianBlur(warped, blurred, cv::Size(0, 0), 0.8);
    rng.fill(frame_noise, cv::RNG::NORMAL, 0.0, 2.0);
    cv::Mat f;
    blurred.convertTo(f, CV_32F);
    f = f.mul(vignetting) + frame_noise;
    // The camera's response curve and a JPEG round trip (photo_like.h).
    s.images.push_back(photoFinish(f));
  }
  return s;
}

} // namespace yawdepth::bench::wall
