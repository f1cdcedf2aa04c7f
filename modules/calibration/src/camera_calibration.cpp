// Camera calibration's driver (what `yawdepth calibrate-camera` calls): the board's detection in the
// images (detectCalibrationViews), and calibrateCamera(), which fits OpenCV's model (camera_fit.cpp),
// chooses the distortion model (model_selection.cpp), measures the coverage and the projection
// uncertainty (calibration_coverage.cpp) and fits ViSP's models (visp_models.cpp).
#include "board_pose.h"
#include "camera_calibration_impl.h"
#include "text.h"

#include <algorithm>
#include <set>
#include <yawdepth/error.h>

namespace yawdepth {

namespace {

using calibration_detail::fixed;

/* Tries a chessboard of another size on a few images: the usual mistake is counting squares. */
std::string sizeHint(const BoardLayout &board, const std::vector<cv::Mat> &images, const DetectorOptions &options)
{
  if (board.pattern.kind != PatternSpec::Kind::Chessboard)
    return {};
  const int c = board.pattern.cols, r = board.pattern.rows;
  // One image only: a failed search costs OpenCV's exhaustive detector a second or so.
  const std::pair<int, int> candidates[] = {{c - 1, r - 1}, {c + 1, r + 1}, {c - 1, r}, {c, r - 1}};
  DetectorOptions fast = options;
  fast.subpixel = false;
  for (std::size_t i = 0; i < images.size() && i < 1; ++i) {
    if (images[i].empty())
      continue;
    for (const auto &cand : candidates) {
      if (cand.first < 3 || cand.second < 3)
        continue;
      PatternSpec p = board.pattern;
      p.cols = cand.first;
      p.rows = cand.second;
      try {
        PatternDetector d(p, fast);
        if (d.detect(images[i], 0).found)
          return "; a " + std::to_string(cand.first) + "x" + std::to_string(cand.second) +
                 " chessboard is there: COLSxROWS counts inner corners (squares minus one), use --pattern " +
                 p.toString();
      } catch (const Error &) {
      }
    }
  }
  return {};
}

/* Notes on few views, poor coverage and outlier views kept. */
void addQualityNotes(CameraCalibration &result)
{
  if (result.views_used < 8)
    result.notes.push_back("only " + std::to_string(result.views_used) +
                           " views used: 10 to 20 views give more reliable parameters");
  if (result.coverage < 0.6)
    result.notes.push_back("the corners cover only " + fixed(100 * result.coverage, 0) +
                           " % of the image: the distortion is poorly known where there are none (see the coverage picture)");
  for (const auto &v : result.views)
    if (v.outlier && v.used)
      result.notes.push_back(v.name + ": outlier view (RMS " + fixed(v.rms_px) + " px); --drop-outliers recalibrates without it");
}

} // namespace

CalibrationDetections detectCalibrationViews(const BoardLayout &board, const std::vector<std::string> &names,
                                             const std::vector<cv::Mat> &images, const DetectorOptions &options,
                                             const std::function<void(std::size_t, std::size_t)> &progress)
{
  if (images.empty())
    throw Error("no calibration images given");
  if (names.size() != images.size())
    throw Error("detectCalibrationViews: " + std::to_string(names.size()) + " names for " +
                std::to_string(images.size()) + " images");
  const std::map<long, Eigen::Vector3d> pts = calibration_detail::boardPoints(board);
  PatternDetector detector(board.pattern, options);
  CalibrationDetections out;
  for (std::size_t i = 0; i < images.size(); ++i) {
    if (progress)
      progress(i, images.size());
    const cv::Mat &img = images[i];
    if (img.empty()) {
      out.failures.push_back(names[i] + ": empty image");
      FrameDetection none;
      none.frame = static_cast<long>(i);
      none.reason = "empty image";
      out.detections.push_back(none);
      continue;
    }
    if (out.width == 0) {
      out.width = img.cols;
      out.height = img.rows;
    } else if (img.cols != out.width || img.rows != out.height) {
      throw Error(names[i] + ": image is " + std::to_string(img.cols) + "x" + std::to_string(img.rows) + " but " +
                  names.front() + " is " + std::to_string(out.width) + "x" + std::to_string(out.height) +
                  ": all calibration images must come from the same camera at the same resolution");
    }
    out.detections.push_back(detector.detect(img, static_cast<long>(i)));
    const FrameDetection &d = out.detections.back();
    for (const std::string &w : d.warnings)
      out.warnings.push_back(names[i] + ": " + w);
    if (!d.found) {
      out.failures.push_back(names[i] + ": " + d.reason);
      continue;
    }
    CalibrationView v;
    v.name = names[i];
    std::vector<long> off_board;
    for (const auto &f : d.features)
      if (pts.count(f.id))
        v.features.push_back(f);
      else
        off_board.push_back(f.id);
    if (!off_board.empty() && board.pattern.kind == PatternSpec::Kind::AprilTag) {
      std::set<long> tags;
      for (long id : off_board)
        tags.insert(id / 5); // pattern.h: tag t has features 5t .. 5t + 4
      std::string list;
      for (long t : tags)
        list += (list.empty() ? "" : " ") + std::to_string(t);
      out.warnings.push_back(names[i] + ": tag(s) " + list + " not on the board (--tags grid, --first-tag-id): ignored");
    }
    if (v.features.size() < 4) {
      out.failures.push_back(names[i] + ": only " + std::to_string(v.features.size()) +
                             " features of the board (tags outside the board's --tags grid?)");
      continue;
    }
    out.views.push_back(std::move(v));
  }
  if (out.views.empty()) {
    std::string msg = "the pattern " + board.pattern.toString() + " was not found in any of the " +
                      std::to_string(images.size()) + " images";
    if (!out.failures.empty())
      msg += " (" + out.failures.front() + ")";
    msg += sizeHint(board, images, options);
    throw Error(msg);
  }
  return out;
}

CameraCalibration calibrateCamera(const BoardLayout &board, const std::vector<CalibrationView> &views, int width,
                                  int height, const CameraCalibrationOptions &options)
{
  if (width <= 0 || height <= 0)
    throw Error("calibrateCamera: unknown image size");
  calibration_detail::CameraFit fit{calibration_detail::boardPoints(board), views, width, height, options, {}, {}};
  CameraCalibration result;
  const std::vector<std::size_t> usable = calibration_detail::collectCorrespondences(fit, result);
  const int min_views = std::max(1, options.min_views);
  if (static_cast<int>(usable.size()) < min_views)
    throw Error("too few views: " + std::to_string(usable.size()) + " usable view(s) of the board, at least " +
                std::to_string(min_views) + " are needed (10 to 20 views at different tilts are best)");
  const calibration_detail::Distortion model = calibration_detail::chooseModel(fit, usable, result);
  std::vector<std::size_t> used = usable;
  const calibration_detail::OpenCvSolution sol =
      calibration_detail::fitDroppingOutliers(fit, model, min_views, used, result);
  result.views_used = static_cast<int>(used.size());
  calibration_detail::storeCamera(fit, sol, model, used, result);
  result.coverage = calibration_detail::coverageOf(fit, used);
  addQualityNotes(result);
  if (options.fit_visp)
    calibration_detail::fitVispModels(fit, sol, used, result);
  return result;
}

} // namespace yawdepth
