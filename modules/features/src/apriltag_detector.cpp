/*!
  \file apriltag_detector.cpp
  \brief AprilTags by ViSP's vpDetectorAprilTag: ids, the four corners and the centre (the
  intersection of the diagonals, on undistorted corners when the camera is known) of each tag.
*/
#include "detector_impl.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>
#include <string>
#include <vector>
#include <visp3/core/vpImage.h>
#include <visp3/core/vpImageConvert.h>
#include <yawdepth/error.h>

namespace yawdepth {

namespace {

vpDetectorAprilTag::vpAprilTagFamily vispFamily(const std::string &family) {
  const std::string f = normalizeAprilTagFamily(family);
  if (f == "36h11")
    return vpDetectorAprilTag::TAG_36h11;
  if (f == "25h9")
    return vpDetectorAprilTag::TAG_25h9;
  if (f == "16h5")
    return vpDetectorAprilTag::TAG_16h5;
  if (f == "circle21h7")
    return vpDetectorAprilTag::TAG_CIRCLE21h7;
#if defined(VISP_HAVE_APRILTAG_BIG_FAMILY)
  if (f == "circle49h12")
    return vpDetectorAprilTag::TAG_CIRCLE49h12;
  if (f == "custom48h12")
    return vpDetectorAprilTag::TAG_CUSTOM48h12;
  if (f == "standard41h12")
    return vpDetectorAprilTag::TAG_STANDARD41h12;
  if (f == "standard52h13")
    return vpDetectorAprilTag::TAG_STANDARD52h13;
#else
  if (f == "circle49h12" || f == "custom48h12" || f == "standard41h12" || f == "standard52h13")
    throw Error("apriltag: family '" + family +
                "' needs ViSP built with the big AprilTag families (VISP_HAVE_APRILTAG_BIG_FAMILY); "
                "this ViSP has 36h11, 25h9, 16h5 and circle21h7");
#endif
  throw Error("apriltag: family '" + family + "' is not supported by ViSP's detector");
}

/*! \brief Tag id from ViSP's message, e.g. "36h11 id: 7"; -1 when absent. */
long tagIdFromMessage(const std::string &msg) {
  const std::size_t k = msg.find("id:");
  if (k == std::string::npos)
    return -1;
  std::istringstream s(msg.substr(k + 3));
  long id = -1;
  if (!(s >> id) || id < 0)
    return -1;
  return id;
}

} // namespace

std::unique_ptr<vpDetectorAprilTag> makeAprilTagDetector(const PatternSpec &pattern, const DetectorOptions &options) {
  auto detector = std::make_unique<vpDetectorAprilTag>(vispFamily(pattern.family));
  detector->setAprilTagQuadDecimate(static_cast<float>(options.apriltag_decimate));
  detector->setAprilTagNbThreads(options.threads);
  detector->setAprilTagRefineEdges(true);
  return detector;
}

FrameDetection PatternDetector::Impl::detectAprilTag(const cv::Mat &gray, long frame) {
  FrameDetection out;
  out.frame = frame;
  vpImage<unsigned char> I;
  cv::Mat cont = gray.isContinuous() ? gray : gray.clone();
  vpImageConvert::convert(cont, I);
  if (!apriltag->detect(I)) {
    out.reason = "no AprilTag of family " + pattern.family + " found";
    return out;
  }
  std::map<long, int> count;
  std::vector<long> ids(apriltag->getNbObjects(), -1);
  for (std::size_t i = 0; i < apriltag->getNbObjects(); ++i) {
    ids[i] = tagIdFromMessage(apriltag->getMessage(i));
    if (ids[i] >= 0)
      ++count[ids[i]];
  }
  for (std::size_t i = 0; i < ids.size(); ++i) {
    if (ids[i] >= 0 && count[ids[i]] > 1) {
      const std::string w = "tag " + std::to_string(ids[i]) + " seen " + std::to_string(count[ids[i]]) +
                             " times in the image: dropped (ambiguous)";
      if (std::find(out.warnings.begin(), out.warnings.end(), w) == out.warnings.end())
        out.warnings.push_back(w);
    }
    if (ids[i] < 0 || count[ids[i]] != 1 || ids[i] > std::numeric_limits<int>::max() / 5 - 1)
      continue; // unreadable or ambiguous (the same tag twice)
    const std::vector<vpImagePoint> &poly = apriltag->getPolygon(i);
    if (poly.size() != 4)
      continue;
    const int tag = static_cast<int>(ids[i]);
    // libapriltag (hence ViSP's polygon) puts pixel centres at half-integers (a pixel's top-left
    // corner is its origin); yawdepth, OpenCV and the camera model put them at integers.
    Eigen::Vector2d c[4];
    for (int k = 0; k < 4; ++k)
      c[k] = Eigen::Vector2d(poly[k].get_u() - 0.5, poly[k].get_v() - 0.5);
    // Centre: the image of the tag's centre, the intersection of the diagonals (exact for a planar
    // square under perspective; done on undistorted points, then distorted back). ViSP's getCog()
    // is the mean of the corners, which perspective biases.
    Eigen::Vector2d centre = 0.25 * (c[0] + c[1] + c[2] + c[3]);
    Eigen::Vector2d m[4];
    bool und = true;
    for (int k = 0; k < 4 && und; ++k)
      und = camera_ok && camera.undistort(c[k], m[k]);
    const auto diagonals = [](const Eigen::Vector2d *p, Eigen::Vector2d &x) {
      const Eigen::Vector2d d1 = p[2] - p[0], d2 = p[3] - p[1], r = p[1] - p[0];
      const double den = d1.x() * d2.y() - d1.y() * d2.x();
      if (!(std::abs(den) > 1e-12 * d1.squaredNorm() * d2.squaredNorm()))
        return false;
      const double t = (r.x() * d2.y() - r.y() * d2.x()) / den;
      x = p[0] + t * d1;
      return x.allFinite();
    };
    Eigen::Vector2d x;
    if (und && diagonals(m, x))
      centre = camera.project(x);
    else if (diagonals(c, x))
      centre = x;
    out.features.push_back(FeatureObservation{aprilTagFeatureId(tag), centre.x(), centre.y()});
    for (int k = 0; k < 4; ++k)
      out.features.push_back(FeatureObservation{aprilTagFeatureId(tag, k), c[k].x(), c[k].y()});
  }
  if (out.features.empty()) {
    out.reason = "AprilTags of family " + pattern.family + " found but none usable (duplicate or unreadable ids)";
    return out;
  }
  std::sort(out.features.begin(), out.features.end(),
            [](const FeatureObservation &a, const FeatureObservation &b) { return a.id < b.id; });
  out.found = true;
  return out;
}

} // namespace yawdepth
