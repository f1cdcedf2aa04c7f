// The PNG of a servo run (servo_sim.h: writePlot).
#include "servo_sim.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace servo_sim {

void writePlot(const std::string &path, const ServoSimOptions &o, const ServoSimResult &r)
{
  static const cv::Scalar kColours[] = {{40, 40, 220}, {40, 160, 40}, {220, 90, 30}, {160, 40, 160}};
  const int W = 640, H = 480, pad = 40;
  cv::Mat img(H + 2 * pad, 2 * W + 3 * pad, CV_8UC3, cv::Scalar(255, 255, 255));
  // Left: image plane.
  const cv::Point off(pad, pad);
  cv::rectangle(img, off, off + cv::Point(W, H), cv::Scalar(0, 0, 0));
  cv::putText(img, "corner trajectories (px), x = desired", off + cv::Point(5, -10), cv::FONT_HERSHEY_SIMPLEX, 0.5,
              cv::Scalar(0, 0, 0));
  const double sx = double(W) / o.camera.width(), sy = double(H) / o.camera.height();
  for (std::size_t i = 0; i < r.desired_pixels.size(); ++i) {
    std::vector<cv::Point> pts;
    for (const auto &st : r.steps)
      if (i < st.pixels.size() && std::isfinite(st.pixels[i].x()))
        pts.emplace_back(off + cv::Point(int(st.pixels[i].x() * sx), int(st.pixels[i].y() * sy)));
    if (pts.size() > 1)
      cv::polylines(img, pts, false, kColours[i % 4], 1, cv::LINE_AA);
    if (!pts.empty())
      cv::circle(img, pts.front(), 4, kColours[i % 4], 1, cv::LINE_AA);
    const cv::Point d = off + cv::Point(int(r.desired_pixels[i].x() * sx), int(r.desired_pixels[i].y() * sy));
    cv::drawMarker(img, d, kColours[i % 4], cv::MARKER_TILTED_CROSS, 10, 2);
  }
  // Right: depth over time.
  const cv::Point off2(2 * pad + W, pad);
  cv::rectangle(img, off2, off2 + cv::Point(W, H), cv::Scalar(0, 0, 0));
  double zmax = 0;
  for (const auto &st : r.steps) {
    for (double z : st.true_Z)
      zmax = std::max(zmax, z);
    for (double z : st.used_Z)
      zmax = std::max(zmax, z);
  }
  zmax = std::max(zmax * 1.1, 0.1);
  const double tmax = std::max(1.0, r.steps.empty() ? 1.0 : r.steps.back().time);
  auto P = [&](double t, double z) {
    return off2 + cv::Point(int(t / tmax * (W - 1)), int((1.0 - std::min(z, zmax) / zmax) * (H - 1)));
  };
  char label[200];
  std::snprintf(label, sizeof label, "depth Z (m) over %.1f s, 0..%.2f m: thin = true, thick = used (%s)", tmax, zmax,
                toString(o.depth));
  cv::putText(img, label, off2 + cv::Point(5, -10), cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(0, 0, 0));
  for (std::size_t i = 0; i < r.desired_pixels.size(); ++i) {
    std::vector<cv::Point> t, u;
    for (const auto &st : r.steps) {
      if (i < st.true_Z.size())
        t.push_back(P(st.time, st.true_Z[i]));
      if (i < st.used_Z.size())
        u.push_back(P(st.time, st.used_Z[i]));
    }
    if (t.size() > 1)
      cv::polylines(img, t, false, kColours[i % 4], 1, cv::LINE_AA);
    if (u.size() > 1)
      cv::polylines(img, u, false, kColours[i % 4], 2, cv::LINE_AA);
  }
  if (!cv::imwrite(path, img))
    std::fprintf(stderr, "servo_ibvs_yawing_camera: cannot write %s\n", path.c_str());
}

} // namespace servo_sim
