#pragma once
// What the report module's figures share (private): text in one font, a figure's PNG bytes for an atomic write.
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>
#include <yawdepth/error.h>

namespace yawdepth {
namespace report_detail {

/* One line of text at `p` (its baseline's left end), anti-aliased. */
inline void text(cv::Mat &img, const std::string &s, cv::Point p, double scale = 0.45,
                 const cv::Scalar &c = cv::Scalar(30, 30, 30), int thickness = 1)
{
  cv::putText(img, s, p, cv::FONT_HERSHEY_SIMPLEX, scale, c, thickness, cv::LINE_AA);
}

/* The figure's PNG bytes; `png` (its file name) for the messages. */
inline std::string encodePng(const cv::Mat &img, const std::string &png)
{
  std::vector<unsigned char> bytes;
  bool ok = false;
  try {
    ok = cv::imencode(".png", img, bytes);
  } catch (const cv::Exception &e) {
    throw Error(png + ": cannot encode the figure: " + e.what());
  }
  if (!ok)
    throw Error(png + ": cannot encode the figure");
  return std::string(bytes.begin(), bytes.end());
}

} // namespace report_detail
} // namespace yawdepth
