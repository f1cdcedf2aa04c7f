/*!
  \file detector.cpp
  \brief PatternDetector: the image checked and made gray, then the chessboard
  (chessboard_detector.cpp) or the AprilTags (apriltag_detector.cpp); tracks from detections and
  the picture of a detection.
*/
#include <yawdepth/features/detector.h>

#include "detector_impl.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>
#include <opencv2/imgproc.hpp>
#include <yawdepth/error.h>

namespace yawdepth {

PatternDetector::PatternDetector(const PatternSpec &pattern, const DetectorOptions &options)
    : impl_(std::make_unique<Impl>()) {
  impl_->pattern = pattern;
  impl_->options = options;
  if (!(options.apriltag_decimate >= 1) || !std::isfinite(options.apriltag_decimate))
    throw Error("detector: the AprilTag decimation must be >= 1");
  if (options.threads < 1)
    throw Error("detector: threads must be >= 1");
  if (options.subpixel_window < 0)
    throw Error("detector: the sub-pixel window must be >= 0");
  if (pattern.kind == PatternSpec::Kind::Chessboard) {
    if (pattern.cols < 3 || pattern.rows < 3 || !(pattern.square > 0))
      throw Error("detector: invalid chessboard pattern " + pattern.toString());
  } else {
    impl_->apriltag = makeAprilTagDetector(pattern, options);
  }
}

void PatternDetector::setCamera(const CameraModel &camera) {
  impl_->camera = camera;
  impl_->camera_ok = true;
}

PatternDetector::~PatternDetector() = default;
PatternDetector::PatternDetector(PatternDetector &&) noexcept = default;
PatternDetector &PatternDetector::operator=(PatternDetector &&) noexcept = default;

FrameDetection PatternDetector::detect(const cv::Mat &image, long frame) {
  FrameDetection out;
  out.frame = frame;
  try {
    if (image.empty()) {
      out.reason = "empty image";
      return out;
    }
    if (image.depth() != CV_8U) {
      out.reason = "unsupported image type (8-bit grayscale or colour expected)";
      return out;
    }
    cv::Mat gray;
    if (image.channels() == 1)
      gray = image;
    else if (image.channels() == 3)
      cv::cvtColor(image, gray, cv::COLOR_BGR2GRAY);
    else if (image.channels() == 4)
      cv::cvtColor(image, gray, cv::COLOR_BGRA2GRAY);
    else {
      out.reason = "unsupported number of channels (" + std::to_string(image.channels()) + ")";
      return out;
    }
    if (gray.cols < 8 || gray.rows < 8) {
      out.reason = "image too small (" + std::to_string(gray.cols) + "x" + std::to_string(gray.rows) + ")";
      return out;
    }
    if (impl_->pattern.kind == PatternSpec::Kind::Chessboard)
      return impl_->detectChessboard(gray, frame);
    return impl_->detectAprilTag(gray, frame);
  } catch (const cv::Exception &e) {
    out.found = false;
    out.features.clear();
    out.reason = std::string("OpenCV error: ") + e.err;
  } catch (const std::exception &e) {
    out.found = false;
    out.features.clear();
    out.reason = std::string("detection error: ") + e.what();
  } catch (...) {
    out.found = false;
    out.features.clear();
    out.reason = "detection error";
  }
  return out;
}

std::vector<Track> PatternDetector::toTracks(const std::vector<FrameDetection> &frames) {
  std::map<long, Track> by_id;
  for (const FrameDetection &f : frames) {
    if (!f.found)
      continue;
    for (const FeatureObservation &d : f.features) {
      Track &t = by_id[d.id];
      t.id = d.id;
      t.observations.push_back(Observation{f.frame, d.u, d.v});
    }
  }
  std::vector<Track> out;
  out.reserve(by_id.size());
  for (auto &kv : by_id) {
    std::stable_sort(kv.second.observations.begin(), kv.second.observations.end(),
                     [](const Observation &a, const Observation &b) { return a.frame < b.frame; });
    out.push_back(std::move(kv.second));
  }
  return out;
}

cv::Mat drawDetection(const cv::Mat &image, const FrameDetection &d) {
  // A gray canvas for what cannot be shown (empty, not 8-bit, odd channel count).
  cv::Mat out(image.empty() ? 480 : image.rows, image.empty() ? 640 : image.cols, CV_8UC3, cv::Scalar(60, 60, 60));
  if (!image.empty() && image.depth() == CV_8U) {
    if (image.channels() == 1)
      cv::cvtColor(image, out, cv::COLOR_GRAY2BGR);
    else if (image.channels() == 4)
      cv::cvtColor(image, out, cv::COLOR_BGRA2BGR);
    else if (image.channels() == 3)
      image.copyTo(out);
  }
  const double scale = std::max(0.35, out.cols / 1800.0);
  const int r = std::max(3, out.cols / 200);
  std::map<long, cv::Point2d> at;
  for (const auto &f : d.features)
    at[f.id] = cv::Point2d(f.u, f.v);
  // chessboard: the first row's direction from corner 0 to corner 1
  if (at.count(0) && at.count(1))
    cv::arrowedLine(out, at[0], at[1], cv::Scalar(0, 200, 0), 1, cv::LINE_AA, 0, 0.2);
  for (const auto &f : d.features) {
    const cv::Point p(static_cast<int>(std::lround(f.u)), static_cast<int>(std::lround(f.v)));
    const cv::Scalar col = f.id == 0 ? cv::Scalar(0, 0, 255) : cv::Scalar(255, 80, 0);
    cv::drawMarker(out, p, col, cv::MARKER_CROSS, 2 * r, 1, cv::LINE_AA);
    cv::putText(out, std::to_string(f.id), p + cv::Point(3, -3), cv::FONT_HERSHEY_SIMPLEX, scale, col, 1, cv::LINE_AA);
  }
  for (const std::string &w : d.warnings) {
    long id = -1;
    if (std::sscanf(w.c_str(), "corner %ld", &id) == 1 && at.count(id))
      cv::circle(out, at[id], 3 * r, cv::Scalar(0, 140, 255), 2, cv::LINE_AA);
  }
  const std::string title = "frame " + std::to_string(d.frame) + ": " +
                            (d.found ? std::to_string(d.features.size()) + " features" : "NOT FOUND: " + d.reason) +
                            (d.warnings.empty() ? std::string() : ", " + std::to_string(d.warnings.size()) + " warning(s)");
  cv::putText(out, title, cv::Point(6, static_cast<int>(18 * scale / 0.35)), cv::FONT_HERSHEY_SIMPLEX, scale * 1.2,
              cv::Scalar(0, 0, 0), 3, cv::LINE_AA);
  cv::putText(out, title, cv::Point(6, static_cast<int>(18 * scale / 0.35)), cv::FONT_HERSHEY_SIMPLEX, scale * 1.2,
              d.found ? cv::Scalar(0, 255, 0) : cv::Scalar(0, 0, 255), 1, cv::LINE_AA);
  return out;
}

} // namespace yawdepth
