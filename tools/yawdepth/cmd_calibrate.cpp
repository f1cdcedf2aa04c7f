// `yawdepth calibrate-camera` and `yawdepth calibrate-rig`: intrinsics and distortion from images of
// a chessboard or an AprilTag grid; camera offset, yaw axis and yaw zero from a static board seen at
// several yaw readings.
#include "commands.h"
#include "progress.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>
#include <visp3/core/vpPoseVector.h>
#include <yawdepth/calibration/camera_calibration.h>
#include <yawdepth/calibration/hand_eye.h>
#include <yawdepth/calibration/rig_calibration.h>
#include <yawdepth/calibration/time_offset.h>
#include <yawdepth/io/recording.h>
#include <yawdepth/camera/camera_file.h>
#include <yawdepth/error.h>
#include <yawdepth/features/detector.h>
#include <yawdepth/io/files.h>

namespace yawdepth::cli {

namespace {

constexpr double kDeg = M_PI / 180.0;

std::string fixed(double v, int precision)
{
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", precision, v);
  return buf;
}

/*! The board of `--pattern` (and, for AprilTag, `--tags COLSxROWS`, `--tag-gap`, `--first-tag-id`). */
BoardLayout makeBoard(const std::string &pattern, const std::string &tags, double tag_gap, int first_tag_id)
{
  BoardLayout board;
  board.pattern = PatternSpec::parse(pattern);
  if (board.pattern.kind == PatternSpec::Kind::AprilTag) {
    int tx = 0, ty = 0;
    char x = 0, extra = 0;
    std::istringstream in(tags);
    if (!(in >> tx >> x >> ty) || (x != 'x' && x != 'X') || (in >> extra) || tx < 1 || ty < 1)
      throw Error("--tags '" + tags + "': expected COLSxROWS, e.g. 4x3");
    board.tags_x = tx;
    board.tags_y = ty;
    board.gap = tag_gap >= 0 ? tag_gap : 0.25 * board.pattern.tag_size;
    board.first_tag_id = first_tag_id;
    board.features(); // validates the layout against the family
  }
  return board;
}

void addBoardOptions(CLI::App *sub, std::string &tags, double &tag_gap, int &first_tag_id)
{
  addTagsOption(sub, tags);
  sub->add_option("--tag-gap", tag_gap, "AprilTag grid: gap between tags (m; default a quarter tag)")
      ->check(FiniteNonNegative);
  sub->add_option("--first-tag-id", first_tag_id, "AprilTag grid: id of the top-left tag")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
}

struct CameraArgs {
  std::string pattern, out, coverage, camera_name = "Camera", tags, distortion = "auto", debug_dir;
  std::vector<std::string> images;
  bool fix_aspect = false, fix_pp = false, drop_outliers = false, k3 = false, zero_tangent = false, quiet = false;
  double tag_gap = -1;
  int first_tag_id = 0;
};

struct RigArgs {
  std::string camera, camera_name, pattern, out, tags;
  MotionOptions motion;
  std::string hand_eye; // --hand-eye eye-in-hand|eye-to-hand, or empty for the yaw rig
  const CLI::Option *max_rms_option = nullptr;
  std::vector<double> initial_offset;
  double initial_yaw_offset = 0, min_yaw_span_deg = 20, tag_gap = -1, max_rms_px = RigCalibrationOptions().max_rms_px;
  int first_tag_id = 0;
  bool board_square = false, fixed_axis = false, quiet = false;
  bool estimate_time_offset = false;
  std::vector<double> time_offset_range = {-0.1, 0.1};
  InputOptions input;
};

/* calibrate-camera's four outputs. */
struct CameraOutputs {
  std::string yaml, ros, xml, coverage;
};

/* The outputs, checked before anything is read or written: none may be an input (an image) or
   another output, and a prefix must name a file ("" or "folder/" would write hidden files such as ./.yaml). */
CameraOutputs cameraOutputs(const CameraArgs &a, const CLI::App &sub)
{
  const std::filesystem::path prefix(a.out);
  if (a.out.empty() || !prefix.has_filename() || prefix.filename() == "." || prefix.filename() == "..")
    throw Error("--out '" + a.out + "': not a file prefix (e.g. --out calib/mycam writes calib/mycam.yaml, "
                "calib/mycam_ros.yaml and calib/mycam.xml)");
  CameraOutputs o;
  o.yaml = a.out + ".yaml";
  o.ros = a.out + "_ros.yaml";
  o.xml = a.out + ".xml";
  o.coverage = sub.count("--coverage") > 0 ? a.coverage : a.out + "_coverage.png";
  std::vector<NamedPath> inputs;
  for (const std::string &path : a.images)
    inputs.push_back({"image", path});
  std::vector<NamedPath> outputs = {{"--out (.yaml)", o.yaml}, {"--out (_ros.yaml)", o.ros}, {"--out (.xml)", o.xml}, {"--coverage", o.coverage}};
  for (const std::string &f : debugFiles(a.debug_dir, a.images))
    outputs.push_back({"--debug-dir", f});
  checkOutputs(inputs, outputs);
  return o;
}

/* The board's views in the images: skipped images and warnings on stderr, --debug-dir's pictures. */
CalibrationDetections detectCameraViews(const CameraArgs &a, const BoardLayout &board)
{
  std::vector<cv::Mat> images;
  {
    ProgressLine progress;
    for (const std::string &path : a.images) {
      progress.count("calibrate-camera", images.size(), a.images.size(), "images read");
      images.push_back(readGrayImage(path));
    }
  }
  stage("calibrate-camera", std::to_string(images.size()) + " images read");
  CalibrationDetections det;
  {
    ProgressLine progress;
    det = detectCalibrationViews(board, a.images, images, DetectorOptions(), [&](std::size_t done, std::size_t total) {
      progress.count("calibrate-camera", done, total, "images searched for the board");
    });
    progress.count("calibrate-camera", images.size(), images.size(), "images searched for the board");
  }
  stage("calibrate-camera", "board searched in " + std::to_string(det.detections.size()) + " images");
  for (const std::string &f : det.failures)
    std::cerr << "calibrate-camera: " << f << " (image skipped)\n";
  for (const std::string &w : det.warnings)
    std::cerr << "calibrate-camera: " << w << "\n";
  if (!a.debug_dir.empty()) {
    const std::vector<std::string> files = debugFiles(a.debug_dir, a.images);
    for (std::size_t i = 0; i < images.size() && i < det.detections.size(); ++i)
      writeDebugImage(files[i], images[i], det.detections[i]);
  }
  return det;
}

/* The options of the fit: --fix-aspect-ratio, --fix-principal-point, --drop-outliers, --distortion
   (or --k3), --zero-tangent. */
CameraCalibrationOptions cameraCalibrationOptions(const CameraArgs &a)
{
  CameraCalibrationOptions opt;
  opt.fix_aspect_ratio = a.fix_aspect;
  opt.fix_principal_point = a.fix_pp;
  opt.drop_outliers = a.drop_outliers;
  using D = CameraCalibrationOptions::Distortion;
  if (a.k3 && a.distortion != "auto" && a.distortion != "k5")
    throw Error("--k3 and --distortion " + a.distortion + " contradict each other");
  opt.distortion = a.k3 || a.distortion == "k5" ? D::K5
                   : a.distortion == "k4"      ? D::K4
                   : a.distortion == "k8"      ? D::K8
                   : a.distortion == "fisheye" ? D::Fisheye
                                               : D::Auto;
  opt.try_fisheye = a.distortion == "auto+fisheye";
  opt.zero_tangential = a.zero_tangent;
  return opt;
}

/* PREFIX.yaml, PREFIX_ros.yaml, PREFIX.xml and the coverage picture: all four files or none. */
void writeCameraFiles(const CameraArgs &a, const CameraOutputs &o, const BoardLayout &board,
                      const CameraCalibration &cal, const CalibrationDetections &det)
{
  std::ostringstream info;
  info << "<calibration_tool>yawdepth calibrate-camera</calibration_tool>"
       << "<nb_calibration_images>" << cal.views_used << "</nb_calibration_images>"
       << "<calibration_pattern>" << board.pattern.toString() << "</calibration_pattern>"
       << "<global_reprojection_error><without_distortion>" << cal.visp_rms_without
       << "</without_distortion><with_distortion>" << cal.visp_rms_with
       << "</with_distortion></global_reprojection_error>";
  if (cal.camera.distortion() == CameraModel::Distortion::KannalaBrandt) // ViSP 3.5 has no fisheye model
    info << "<lens_model>Kannala-Brandt fisheye: ViSP cannot represent it; these are ViSP's own pinhole and "
            "kud/kdu models fitted to the same corners, an approximation (see their errors above); the fisheye "
            "model is in the OpenCV and ROS YAML files</lens_model>";
  AtomicFiles files;
  files.add(o.yaml, cameraYamlText(cal.camera));
  files.add(o.ros, rosCameraInfoYamlText(cal.camera, a.camera_name));
  files.add(o.xml, vispCameraXmlText(cal, a.camera_name, info.str()));
  const std::string ext = std::filesystem::path(o.coverage).extension().string();
  files.add(o.coverage, coverageImageBytes(cal, det.views, ext.empty() ? std::string(".png") : ext));
  files.commit();
}

/* The distortion model's reason, then the models compared. */
void printDistortionModels(const CameraCalibration &cal)
{
  std::cout << "Distortion model: " << cal.model_reason << "\n";
  if (cal.models.size() > 1)
    for (const auto &m : cal.models)
    {
      std::cout << "  " << (m.chosen ? "* " : "  ") << m.name << ": RMS " << fixed(m.rms_px, 4)
                << " px, on views left out " << fixed(m.heldout_rms_px, 4) << " px";
      if (m.inadmissible.empty())
        std::cout << ", projection uncertainty " << fixed(m.image_uncertainty_px, 4) << " px, expected error "
                  << fixed(m.score_px, 4) << " px\n";
      else
        std::cout << "; not usable: " << m.inadmissible << "\n";
    }
}

/* The OpenCV model with its 1-sigma uncertainties, then the distortion models compared. */
void printCameraModel(const CameraCalibration &cal, bool fixed_principal_point)
{
  const CameraModel &c = cal.camera;
  const std::vector<double> &sd = cal.std_devs;
  auto pm = [](double v, double s, int p) { return fixed(v, p) + " +- " + fixed(s, p); };
  const auto intrinsics = [&](const char *model) {
    std::cout << "Camera (OpenCV, " << model << "), 1-sigma:\n"
              << "  fx = " << pm(c.kx(), sd[0], 2) << " px   fy = " << pm(c.ky(), sd[1], 2) << " px\n"
              << "  u0 = " << pm(c.u0(), sd[2], 2) << " px   v0 = " << pm(c.v0(), sd[3], 2) << " px"
              << (fixed_principal_point ? " (fixed)" : "") << "\n";
  };
  if (c.distortion() == CameraModel::Distortion::KannalaBrandt)
  { // std_devs holds fx fy u0 v0 k1..k4 in its first eight places
    const std::vector<double> &kb = c.kannalaBrandtCoefficients();
    intrinsics("Kannala-Brandt fisheye model");
    std::cout << "  k1 = " << pm(kb[0], sd[4], 5) << "   k2 = " << pm(kb[1], sd[5], 5) << "\n"
              << "  k3 = " << pm(kb[2], sd[6], 5) << "   k4 = " << pm(kb[3], sd[7], 5) << "\n";
    printDistortionModels(cal);
    return;
  }
  const std::vector<double> &k = c.brownCoefficients();
  intrinsics("Brown model");
  std::cout << "  k1 = " << pm(k[0], sd[4], 5) << "   k2 = " << pm(k[1], sd[5], 5) << "\n"
            << "  p1 = " << pm(k[2], sd[6], 6) << "   p2 = " << pm(k[3], sd[7], 6) << "\n"
            << "  k3 = " << pm(k[4], sd[8], 5) << (k[4] != 0 ? "" : " (fixed)");
  if (k[5] != 0 || k[6] != 0 || k[7] != 0)
    std::cout << "   k4 = " << pm(k[5], sd[9], 5) << "   k5 = " << pm(k[6], sd[10], 5) << "   k6 = " << pm(k[7], sd[11], 5);
  std::cout << "\n";
  printDistortionModels(cal);
}

/* After the RMS line (unless --quiet): the model, the projection uncertainty, each view, ViSP's
   models, the board's coverage, the notes, the files written. */
void printCameraCalibration(const CameraArgs &a, const CameraOutputs &o, const CameraCalibration &cal)
{
  printCameraModel(cal, a.fix_pp);
  const CameraModel &c = cal.camera;
  if (cal.uncertainty_grid.size() == 48) {
    const double centre = projectionUncertainty(cal, 0.5 * (c.width() - 1), 0.5 * (c.height() - 1));
    const double worst = *std::max_element(cal.uncertainty_grid.begin(), cal.uncertainty_grid.end());
    std::cout << "Projection uncertainty (1 sigma, px): " << fixed(centre, 4) << " at the centre, up to "
              << fixed(worst, 4) << " over an 8 x 6 grid of the image (per cell in the coverage picture)\n";
  }
  std::cout << "Per view (RMS reprojection error, board tilt):\n";
  for (const auto &v : cal.views) {
    std::cout << "  " << v.name << ": " << v.points << " points";
    if (v.points > 0 && (v.used || v.outlier))
      std::cout << ", " << fixed(v.rms_px, 4) << " px, tilt " << fixed(v.tilt / kDeg, 1) << " deg";
    if (v.outlier)
      std::cout << (v.used ? "  OUTLIER" : "  OUTLIER, dropped");
    else if (!v.used)
      std::cout << "  not used";
    std::cout << "\n";
  }
  const vpCameraParameters &w0 = cal.visp_without, &w1 = cal.visp_with;
  std::cout << "ViSP model without distortion: px = " << fixed(w0.get_px(), 2) << " py = " << fixed(w0.get_py(), 2)
            << " u0 = " << fixed(w0.get_u0(), 2) << " v0 = " << fixed(w0.get_v0(), 2) << ", RMS "
            << fixed(cal.visp_rms_without, 4) << " px\n"
            << "ViSP model with distortion:    px = " << fixed(w1.get_px(), 2) << " py = " << fixed(w1.get_py(), 2)
            << " u0 = " << fixed(w1.get_u0(), 2) << " v0 = " << fixed(w1.get_v0(), 2)
            << " kud = " << fixed(w1.get_kud(), 5) << " kdu = " << fixed(w1.get_kdu(), 5) << ", RMS "
            << fixed(cal.visp_rms_with, 4) << " px (kud), " << fixed(cal.visp_rms_kdu, 4) << " px (kdu)\n";
  std::cout << "Board orientations differ by up to " << fixed(cal.orientation_spread / kDeg, 1)
            << " deg; corners cover " << fixed(100 * cal.coverage, 0) << " % of the image (" << o.coverage << ")\n";
  for (const std::string &n : cal.notes)
    std::cout << "note: " << n << "\n";
  std::cout << "wrote " << o.yaml << ", " << o.ros << ", " << o.xml << "\n";
}

int runCalibrateCamera(const CameraArgs &a, const CLI::App &sub)
{
  const CameraOutputs outputs = cameraOutputs(a, sub);
  const BoardLayout board = makeBoard(a.pattern, a.tags, a.tag_gap, a.first_tag_id);
  const CalibrationDetections det = detectCameraViews(a, board);
  const CameraCalibrationOptions opt = cameraCalibrationOptions(a);
  const CameraCalibration cal = calibrateCamera(board, det.views, det.width, det.height, opt);
  stage("calibrate-camera", "fitted on " + std::to_string(det.views.size()) + " views");
  if (!cal.visp_fitted) {
    std::string why;
    for (const auto &n : cal.notes)
      if (n.rfind("ViSP", 0) == 0)
        why = n;
    throw Error("cannot fit ViSP's camera models" + (why.empty() ? std::string() : ": " + why));
  }
  std::size_t points = 0;
  for (const auto &v : cal.views)
    if (v.used)
      points += static_cast<std::size_t>(v.points);
  writeCameraFiles(a, outputs, board, cal, det);
  std::cout << "RMS reprojection error: " << fixed(cal.rms_px, 4) << " px (" << cal.views_used << " views, "
            << points << " points)\n";
  if (!a.quiet)
    printCameraCalibration(a, outputs, cal);
  return 0;
}

} // namespace

Runner addCalibrateCamera(CLI::App &app)
{
  auto a = std::make_shared<CameraArgs>();
  CLI::App *sub = app.add_subcommand(
      "calibrate-camera",
      "Calibrate a camera from images of a chessboard (or an AprilTag grid): writes PREFIX.yaml (OpenCV, Brown or "
      "fisheye model), PREFIX_ros.yaml (ROS camera_info) and PREFIX.xml (ViSP, without and with kud/kdu distortion) and prints the RMS reprojection error.");
  sub->add_option("--pattern", a->pattern, "chessboard:COLSxROWS:SQUARE (inner corners, metres) or apriltag:FAMILY:SIZE")
      ->required();
  sub->add_flag("--fix-aspect-ratio", a->fix_aspect, "Keep fx = fy");
  sub->add_flag("--fix-principal-point", a->fix_pp,
                "Keep the principal point at the image centre (OpenCV model; ViSP's models fit it)");
  sub->add_option("--out", a->out, "Output prefix: writes PREFIX.yaml (OpenCV), PREFIX_ros.yaml (ROS camera_info) and "
                  "PREFIX.xml (ViSP), all or none")->required();
  sub->add_option("images", a->images, "Calibration images")->required();
  sub->add_flag("--drop-outliers", a->drop_outliers,
                "Recalibrate without the outlier views (RMS above 3x the median and above 0.5 px)");
  sub->add_option("--coverage", a->coverage, "Coverage picture (default PREFIX_coverage.png)");
  sub->add_option("--debug-dir", a->debug_dir,
                  "Write each image with its detected features and ids drawn (DIR/NNNN_NAME.png, NNNN its position)");
  sub->add_option("--camera-name", a->camera_name, "Camera name in the ViSP XML and the ROS camera_info YAML")->capture_default_str();
  sub->add_option("--distortion", a->distortion,
                  "Distortion model: k4 (k1 k2 p1 p2), k5 (+ k3), k8 (rational, k1..k6 p1 p2), fisheye "
                  "(Kannala-Brandt k1..k4, cv::fisheye), auto: the Brown model (k4, k5 or k8) with the least "
                  "expected error on views left out, never fisheye, or auto+fisheye: the same with fisheye among "
                  "them")
      ->check(CLI::IsMember({"auto", "auto+fisheye", "k4", "k5", "k8", "fisheye"}))
      ->capture_default_str();
  sub->add_flag("--k3", a->k3, "The same as --distortion k5");
  sub->add_flag("--zero-tangent", a->zero_tangent, "Fix the tangential distortion p1 = p2 = 0");
  addVerbosityOptions(sub, a->quiet, "Print only the RMS reprojection error, no progress");
  addBoardOptions(sub, a->tags, a->tag_gap, a->first_tag_id);
  return [a, sub]() { return runCalibrateCamera(*a, *sub); };
}

namespace {

/* --hand-eye's options: the setup, --max-rms-px when given. */
HandEyeOptions handEyeOptions(const RigArgs &a)
{
  HandEyeOptions opt;
  opt.setup = handEyeSetupFromString(a.hand_eye);
  if (a.max_rms_option != nullptr && a.max_rms_option->count() > 0)
    opt.max_rms_px = a.max_rms_px;
  return opt;
}

/* The board scale check's line, and its warning on stderr for a mismatch. */
void printBoardScale(const BoardScaleCheck &c, const char *source)
{
  if (c.status == BoardScaleStatus::NotEstimated)
    return;
  std::cout << "board scale (from " << source << "): " << fixed(c.scale, 4) << " +- " << fixed(c.sigma, 4)
            << " times the size given (" << toString(c.status) << ")";
  if (c.distance_spread > 0)
    std::cout << "; the views' distances to the board spread by " << fixed(1000 * c.distance_spread, 1) << " mm";
  std::cout << "\n";
  if (c.status == BoardScaleStatus::Mismatch || c.status == BoardScaleStatus::Unconfirmed)
    std::cerr << "calibrate-rig: warning: " << c.message << "\n";
}

/* The hand-eye result as fitted. */
void printHandEye(const RigArgs &a, const HandEyeCalibration &cal)
{
  const bool in_hand = cal.setup == HandEyeSetup::EyeInHand;
  const vpPoseVector X(cal.camera_pose), X0(cal.initial_camera_pose), Y(cal.target_pose);
  const Eigen::Matrix<double, 6, 1> &sx = cal.camera_pose_sigma;
  auto pose = [](const vpPoseVector &p) {
    std::ostringstream s;
    s << "t = (" << fixed(1000 * p[0], 2) << ", " << fixed(1000 * p[1], 2) << ", " << fixed(1000 * p[2], 2)
      << ") mm, theta-u = (" << fixed(p[3], 5) << ", " << fixed(p[4], 5) << ", " << fixed(p[5], 5) << ") rad";
    return s.str();
  };
  std::cout << "calibrate-rig --hand-eye " << a.hand_eye << ": " << cal.views << " views, " << cal.points
            << " corners\n";
  for (const std::string &skip : cal.skipped)
    std::cerr << "calibrate-rig: " << skip << " (view left out)\n";
  std::cout << (in_hand ? "eMc" : "rMc") << " (camera pose, 1-sigma): " << pose(X) << "\n";
  std::cout << "  +- (" << fixed(1000 * sx(0), 2) << ", " << fixed(1000 * sx(1), 2) << ", " << fixed(1000 * sx(2), 2)
            << ") mm, (" << fixed(sx(3) / kDeg, 3) << ", " << fixed(sx(4) / kDeg, 3) << ", " << fixed(sx(5) / kDeg, 3)
            << ") deg\n";
  std::cout << "vpHandEyeCalibration start: " << pose(X0) << "\n";
  std::cout << (in_hand ? "rMo" : "eMo") << " (board pose): " << pose(Y) << "\n";
  std::cout << "RMS reprojection error: " << fixed(cal.rms_px, 4) << " px (" << fixed(cal.initial_rms_px, 4)
            << " px at the start); per view:";
  for (double r : cal.view_rms_px)
    std::cout << " " << fixed(r, 2);
  std::cout << "\n";
  printBoardScale(cal.board_scale, "the hand's motion");
  std::cout << "wrote " << a.out << "\n";
}

/* calibrate-rig --hand-eye: the fit, the rig file, the report. */
int runHandEye(const RigArgs &a, const CameraModel &camera, const BoardLayout &board,
               const std::vector<HandEyeView> &views)
{
  const HandEyeCalibration cal = calibrateHandEye(camera, board, views, handEyeOptions(a));
  stage("calibrate-rig", "hand-eye fitted on " + std::to_string(views.size()) + " views");
  writeFileAtomically(a.out, handEyeRigYaml(cal));
  printHandEye(a, cal);
  return 0;
}

/* The board's views: one per image of the motion log where the pattern is found, for the yaw rig
   (`views`) and for --hand-eye (`hand_eye_views`); the frames skipped on stderr unless --quiet. */
void detectRigViews(const RigArgs &a, const CameraModel &camera, const BoardLayout &board, const MotionLog &motion,
                    std::vector<RigView> &views, std::vector<HandEyeView> &hand_eye_views)
{
  PatternDetector detector(board.pattern);
  detector.setCamera(camera);
  std::vector<std::string> failures;
  ProgressLine progress;
  for (std::size_t i = 0; i < motion.samples.size(); ++i) {
    progress.count("calibrate-rig", i, motion.samples.size(), "images searched for the board");
    const long frame = motion.samples[i].frame;
    if (motion.images[i].empty()) {
      failures.push_back("frame " + std::to_string(frame) + ": no image");
      continue;
    }
    const cv::Mat image = readGrayImage(motion.images[i], camera);
    const FrameDetection d = detector.detect(image, frame);
    if (!d.found) {
      failures.push_back("frame " + std::to_string(frame) + ": " + d.reason);
      continue;
    }
    views.push_back({motion.samples[i], d.features});
    hand_eye_views.push_back({wMv(motion.samples[i]), d.features, motion.images[i]});
  }
  progress.finish();
  stage("calibrate-rig", "board found in " + std::to_string(views.size()) + " of " +
                             std::to_string(motion.samples.size()) + " images");
  if (views.empty())
    throw Error("the pattern " + board.pattern.toString() + " was not found in any of the " +
                std::to_string(motion.samples.size()) + " images" +
                (failures.empty() ? std::string() : " (" + failures.front() + ")"));
  if (!a.quiet)
    for (const std::string &f : failures)
      std::cerr << "calibrate-rig: " << f << " (frame skipped)\n";
}

/* The yaw rig fit's options: --initial-offset, --initial-yaw-offset, --board-square, --fixed-axis,
   --min-yaw-span, --max-rms-px. */
RigCalibrationOptions rigCalibrationOptions(const RigArgs &a)
{
  RigCalibrationOptions opt;
  if (!a.initial_offset.empty()) {
    opt.initial_offset = Eigen::Vector3d(a.initial_offset[0], a.initial_offset[1], a.initial_offset[2]);
    opt.use_initial_offset = true;
  }
  opt.initial_yaw_offset = a.initial_yaw_offset;
  opt.board_square = a.board_square;
  opt.estimate_axis = !a.fixed_axis;
  opt.min_yaw_span = a.min_yaw_span_deg * kDeg;
  opt.max_rms_px = a.max_rms_px;
  return opt;
}

/* The yaw rig as fitted, with its uncertainties. */
void printRigCalibration(const RigArgs &a, const RigCalibration &rig)
{
  const Eigen::Vector3d &t = rig.camera_offset, &st = rig.camera_offset_sigma;
  const Eigen::Vector3d &ax = rig.yaw_axis, &sa = rig.yaw_axis_sigma;
  std::cout << "calibrate-rig: " << rig.views << " views, " << rig.points << " points, yaw readings spanning "
            << fixed(rig.yaw_span / kDeg, 1) << " deg (" << rig.distinct_yaws << " distinct), robot translation "
            << fixed(1000 * rig.baseline, 1) << " mm\n";
  std::cout << "camera offset t0 (mm, 1-sigma): x = " << fixed(1000 * t.x(), 2) << " +- " << fixed(1000 * st.x(), 2)
            << ", y = " << fixed(1000 * t.y(), 2) << " (along the yaw axis: not observable, kept), z = "
            << fixed(1000 * t.z(), 2) << " +- " << fixed(1000 * st.z(), 2) << "; distance from the axis "
            << fixed(1000 * std::hypot(t.x(), t.z()), 2) << " mm\n";
  std::cout << "yaw offset (true yaw = reading + offset): " << fixed(rig.yaw_offset / kDeg, 4) << " deg";
  if (rig.yaw_zero == YawZeroSource::Fixed)
    std::cout << " (not observable: the robot did not move and --board-square was not given; kept)\n";
  else
    std::cout << " +- " << fixed(rig.yaw_offset_sigma / kDeg, 4) << " deg ("
              << (rig.yaw_zero == YawZeroSource::RobotMotion ? "from the robot's translation"
                                                             : "from the board standing square")
              << ")\n";
  std::cout << "yaw axis (vision frame): (" << fixed(ax.x(), 5) << ", " << fixed(ax.y(), 5) << ", " << fixed(ax.z(), 5)
            << ") +- (" << fixed(sa.x(), 5) << ", " << fixed(sa.y(), 5) << ", " << fixed(sa.z(), 5) << "), "
            << fixed(std::acos(std::min(1.0, ax.y())) / kDeg, 3) << " deg from +Y"
            << (a.fixed_axis ? " (fixed)" : "") << "\n";
  std::cout << "RMS reprojection error: " << fixed(rig.rms_px, 4) << " px\n";
  printBoardScale(rig.board_scale, "the robot's translation");
  std::cout << "wrote " << a.out << "\n";
}

/* A number with 17 significant digits (the rig file's precision). */
std::string formatSeconds(double v)
{
  char b[40];
  std::snprintf(b, sizeof b, "%.17g", v);
  return b;
}

/* The rig file's time offset lines. */
std::string timeOffsetYaml(const TimeOffsetEstimate &e)
{
  return "# the image at camera time t was taken at motion time t + time_offset (s)\ntime_offset: " +
         formatSeconds(e.offset) + "\ntime_offset_sigma: " + formatSeconds(e.sigma) + "\n";
}

/* --estimate-time-offset: the yaw rig (or, with --hand-eye, the camera on the arm) and the time offset
   from a timestamped log and timed images. */
int runCalibrateRigWithTimeOffset(const RigArgs &a, const CameraModel &camera, const BoardLayout &board)
{
  const MotionInput in = a.motion.input();
  const MotionLog motion = readMotionFile(in.motion, in.format, std::nullopt, a.input.limits());
  if (!motion.timestamped)
    throw Error(a.motion.name() + ": --estimate-time-offset needs a timestamped motion log (t, TUM or EuRoC) and --images");
  if (in.images.empty())
    throw Error("--estimate-time-offset needs --images: the images and their times");
  if (!a.hand_eye.empty() && !motion.samples.front().six_dof)
    throw Error(a.motion.name() + ": --hand-eye needs the hand's 6-DoF poses (TUM, EuRoC, or t,tx,ty,tz,tux,tuy,tuz), "
                "not a planar log");
  const ImageList images = readImageList(in.images, true, a.input.limits());
  {
    std::vector<NamedPath> inputs = a.motion.inputs();
    inputs.push_back({"--camera", a.camera});
    for (const std::string &image : images.paths)
      inputs.push_back({"--images' image", image});
    checkOutputs(inputs, {{"--out", a.out}});
  }
  PatternDetector detector(board.pattern);
  detector.setCamera(camera);
  std::vector<std::vector<FeatureObservation>> features(images.paths.size());
  for (std::size_t i = 0; i < images.paths.size(); ++i) {
    const FrameDetection d = detector.detect(readGrayImage(images.paths[i], camera), static_cast<long>(i));
    if (d.found)
      features[i] = d.features;
    else if (!a.quiet)
      std::cerr << "calibrate-rig: " << images.paths[i] << ": " << d.reason << " (image skipped)\n";
  }
  TimeOffsetSearch search;
  search.min = a.time_offset_range[0];
  search.max = a.time_offset_range[1];
  const auto printOffset = [&](const TimeOffsetEstimate &e, int used) {
    std::cout << "time offset: " << fixed(1e3 * e.offset, 3) << " +- " << fixed(1e3 * e.sigma, 3) << " ms (" << used
              << " images with a pose over the range searched, " << e.evaluations << " fits)\n";
  };
  if (!a.hand_eye.empty()) {
    const TimedHandEyeCalibration cal = calibrateHandEyeWithTimeOffset(
        camera, board, motion, images.times, features, images.paths, handEyeOptions(a), search, in.max_pose_gap);
    writeFileAtomically(a.out, handEyeRigYaml(cal.hand_eye) + timeOffsetYaml(cal.time_offset));
    printOffset(cal.time_offset, cal.images_used);
    printHandEye(a, cal.hand_eye);
    return 0;
  }
  const TimedRigCalibration cal = calibrateRigWithTimeOffset(camera, board, motion, images.times, features,
                                                             rigCalibrationOptions(a), search, in.max_pose_gap);
  writeFileAtomically(a.out, rigCalibrationYaml(cal.rig) + timeOffsetYaml(cal.time_offset));
  printOffset(cal.time_offset, cal.images_used);
  printRigCalibration(a, cal.rig);
  return 0;
}

int runCalibrateRig(const RigArgs &a)
{
  const BoardLayout board = makeBoard(a.pattern, a.tags, a.tag_gap, a.first_tag_id);
  const CameraModel camera = loadCameraFile(a.camera, a.camera_name);
  if (a.estimate_time_offset)
    return runCalibrateRigWithTimeOffset(a, camera, board);
  const MotionLog motion = loadCommandMotion("calibrate-rig", a.motion, nullptr, a.input.limits(), a.quiet).log;
  if (motion.images.empty())
    throw Error(a.motion.name() + ": no 'image' column: calibrate-rig needs the image of each frame");
  if (!a.hand_eye.empty() && !motion.samples.front().six_dof)
    throw Error(a.motion.name() + ": --hand-eye needs the hand's 6-DoF poses (columns tx,ty,tz,tux,tuy,tuz), not a planar "
                "log");
  {
    std::vector<NamedPath> inputs = a.motion.inputs();
    inputs.push_back({"--camera", a.camera});
    for (const std::string &image : motion.images)
      if (!image.empty())
        inputs.push_back({"--motion's image", image});
    checkOutputs(inputs, {{"--out", a.out}});
  }
  std::vector<RigView> views;
  std::vector<HandEyeView> hand_eye_views;
  detectRigViews(a, camera, board, motion, views, hand_eye_views);
  if (!a.hand_eye.empty())
    return runHandEye(a, camera, board, hand_eye_views);
  const RigCalibration rig = calibrateRig(camera, board, views, rigCalibrationOptions(a));
  stage("calibrate-rig", "rig fitted on " + std::to_string(views.size()) + " views");
  writeFileAtomically(a.out, rigCalibrationYaml(rig));
  printRigCalibration(a, rig);
  return 0;
}

} // namespace

Runner addCalibrateRig(CLI::App &app)
{
  auto a = std::make_shared<RigArgs>();
  CLI::App *sub = app.add_subcommand(
      "calibrate-rig",
      "Calibrate the yaw rig from images of a static board at several yaw readings: camera offset from the yaw "
      "axis (Lb), yaw axis direction, zero of the yaw reading, with uncertainties; writes the rig file. With "
      "--hand-eye: the camera's pose on a robot arm (eMc, or rMc for eye-to-hand) from a 6-DoF motion log of the "
      "hand's poses, written as the rig file's camera_pose.");
  addCameraOptions(sub, a->camera, a->camera_name, true, "calibrated (calibrate-camera)");
  addMotionOptions(sub, a->motion,
                   "Motion log with the yaw readings and an image column (frame,x,y,z,heading,yaw,image); with "
                   "--hand-eye, the hand's pose in the robot base per image (frame,tx,ty,tz,tux,tuy,tuz,image, or "
                   "ViSP pose files with --images)");
  CLI::Option *hand_eye =
      sub->add_option("--hand-eye", a->hand_eye,
                      "Hand-eye calibration instead of the yaw rig: eye-in-hand (camera on the hand, board fixed) "
                      "or eye-to-hand (camera fixed, board on the hand)")
          ->check(CLI::IsMember({"eye-in-hand", "eye-to-hand"}));
  sub->add_option("--pattern", a->pattern, "chessboard:COLSxROWS:SQUARE or apriltag:FAMILY:SIZE (metres)")->required();
  sub->add_option("--out", a->out, "Output rig file (YAML)")->required();
  sub->add_option("--initial-offset", a->initial_offset,
                  "Start for the camera offset x,y,z (m); y, along the yaw axis, is not observable and is kept")
      ->expected(3)
      ->delimiter(',')
      ->check(Finite);
  sub->add_option("--initial-yaw-offset", a->initial_yaw_offset,
                  "Start for the yaw offset (rad); kept when the images cannot tell it")
      ->check(Finite)
      ->capture_default_str();
  sub->add_flag("--board-square", a->board_square,
                "The board stands square to the robot's forward direction: estimate the yaw zero from it");
  sub->add_flag("--fixed-axis", a->fixed_axis, "Take the yaw axis as the vision frame's +Y instead of estimating it");
  // In degrees (a span is read and typed in degrees), so the name says so; --min-yaw-span was its old name.
  renamedFrom(sub,
              sub->add_option("--min-yaw-span-deg,--min-yaw-span", a->min_yaw_span_deg,
                              "Smallest accepted span of the yaw readings (deg; --min-yaw-span is its old name)")
                  ->check(FiniteNonNegative)
                  ->capture_default_str(),
              "--min-yaw-span");
  a->max_rms_option = sub->add_option("--max-rms-px", a->max_rms_px,
                                      "A fit with a larger reprojection RMS failed and writes nothing (px; with "
                                      "--hand-eye the default is 20: arm kinematics err by millimetres)")
                           ->check(CLI::PositiveNumber & Finite)
                           ->capture_default_str();
  addVerbosityOptions(sub, a->quiet, "No progress or per-frame detection messages");
  sub->add_flag("--estimate-time-offset", a->estimate_time_offset,
                "Estimate the time offset between the camera's clock and the motion log's with the rig or, with "
                "--hand-eye, the arm (a timestamped log and --images; the pan must sweep back and forth, the arm "
                "change speed, while the board is seen); written as the rig file's time_offset and time_offset_sigma");
  sub->add_option("--time-offset-range", a->time_offset_range, "The offsets searched by --estimate-time-offset: MIN,MAX (s)")
      ->expected(2)
      ->delimiter(',')
      ->check(Finite)
      ->capture_default_str();
  addInputOptions(sub, a->input);
  addBoardOptions(sub, a->tags, a->tag_gap, a->first_tag_id);
  sub->get_option("--time-offset-range")->needs("--estimate-time-offset");
  sub->get_option("--estimate-time-offset")->excludes("--time-offset");
  for (const char *rig_only : {"--initial-offset", "--initial-yaw-offset", "--board-square", "--fixed-axis", "--min-yaw-span-deg"})
    hand_eye->excludes(rig_only);
  return [a]() { return runCalibrateRig(*a); };
}

} // namespace yawdepth::cli
