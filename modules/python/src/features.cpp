// Detection and tracking on numpy images (uint8, 2-D, as OpenCV's Python API gives them), and the
// error analysis of eqs. (9)-(17).
#include "common.h"

#include <cstring>
#include <opencv2/core.hpp>
#include <yawdepth/calibration/camera_calibration.h>
#include <yawdepth/calibration/hand_eye.h>
#include <yawdepth/calibration/rig_calibration.h>
#include <yawdepth/error.h>
#include <yawdepth/estimation/error_analysis.h>
#include <yawdepth/features/detector.h>
#include <yawdepth/features/klt_tracker.h>
#include <yawdepth/features/pattern.h>

namespace yawdepth::python {

namespace {

using Image = py::array_t<std::uint8_t, py::array::c_style | py::array::forcecast>;

/*! A cv::Mat over the numpy image's pixels (no copy; valid while `image` lives). */
cv::Mat matOf(const Image &image)
{
  if (image.ndim() != 2)
    throw Error("image: expected a 2-D uint8 array (gray), got " + std::to_string(image.ndim()) + " dimensions");
  return cv::Mat(static_cast<int>(image.shape(0)), static_cast<int>(image.shape(1)), CV_8UC1,
                 const_cast<std::uint8_t *>(image.data()));
}

/*! An 8-bit gray cv::Mat as a (rows, cols) uint8 array (copied). */
py::array_t<std::uint8_t> imageOf(const cv::Mat &m)
{
  if (m.type() != CV_8UC1)
    throw Error("image: not 8-bit gray");
  py::array_t<std::uint8_t> a({static_cast<py::ssize_t>(m.rows), static_cast<py::ssize_t>(m.cols)});
  for (int r = 0; r < m.rows; ++r)
    std::memcpy(a.mutable_data(r, 0), m.ptr(r), static_cast<std::size_t>(m.cols));
  return a;
}

Array featuresArray(const std::vector<FeatureObservation> &f)
{
  Array a = newArray(static_cast<py::ssize_t>(f.size()), 3);
  auto r = a.mutable_unchecked<2>();
  for (std::size_t i = 0; i < f.size(); ++i) {
    const py::ssize_t k = static_cast<py::ssize_t>(i);
    r(k, 0) = static_cast<double>(f[i].id);
    r(k, 1) = f[i].u;
    r(k, 2) = f[i].v;
  }
  return a;
}

py::dict statsOf(const KltStats &s)
{
  py::dict d;
  d["tracked"] = s.tracked;
  d["lost_flow"] = s.lost_flow;
  d["lost_fb"] = s.lost_fb;
  d["lost_border"] = s.lost_border;
  d["lost_epipolar"] = s.lost_epipolar;
  d["detected"] = s.detected;
  d["guided"] = s.guided;
  d["lost_ambiguous"] = s.lost_ambiguous;
  d["lost_appearance"] = s.lost_appearance;
  d["split_jump"] = s.split_jump;
  return d;
}

} // namespace

void bindFeatures(py::module_ &m)
{
  m.def("readGrayImage", [](const std::string &path, const std::optional<CameraModel> &camera) {
          return imageOf(camera ? readGrayImage(path, *camera) : readGrayImage(path));
        }, py::arg("path"), py::arg("camera") = py::none(),
        "Read an image file as (rows, cols) uint8 gray; with `camera`, its size must be the camera's.");

  py::class_<DetectorOptions>(m, "DetectorOptions", "Options of PatternDetector (C++ DetectorOptions, its defaults): "
                              "subpixel, subpixel_window (px, 0: per corner), apriltag_decimate, threads.")
      .def(py::init<>())
      .def_readwrite("subpixel", &DetectorOptions::subpixel)
      .def_readwrite("subpixel_window", &DetectorOptions::subpixel_window)
      .def_readwrite("apriltag_decimate", &DetectorOptions::apriltag_decimate)
      .def_readwrite("threads", &DetectorOptions::threads);

  py::class_<FrameDetection>(m, "FrameDetection", R"doc(
One image's detection: frame, found (bool), reason (str, why not found), features (K, 3) float64
[id, u (px), v (px)] (observed pixels), warnings (list of str).)doc")
      .def_readonly("frame", &FrameDetection::frame)
      .def_readonly("found", &FrameDetection::found)
      .def_readonly("reason", &FrameDetection::reason)
      .def_property_readonly("features", [](const FrameDetection &d) { return featuresArray(d.features); })
      .def_readonly("warnings", &FrameDetection::warnings);

  py::class_<PatternDetector>(m, "PatternDetector", R"doc(
Detects a pattern in gray images with stable feature ids (what `yawdepth measure --pattern` runs).
PatternDetector(pattern, options=DetectorOptions()): pattern as the CLI's --pattern,
'chessboard:COLSxROWS:SQUARE' or 'apriltag:FAMILY:SIZE' (m).)doc")
      .def(py::init([](const std::string &pattern, const DetectorOptions &o) {
             return PatternDetector(PatternSpec::parse(pattern), o);
           }),
           py::arg("pattern"), py::arg("options") = DetectorOptions())
      .def("setCamera", &PatternDetector::setCamera, py::arg("camera"),
           "The camera (lens-aware corner search), as the CLI sets it.")
      .def("detect",
           [](PatternDetector &d, const Image &image, long frame) {
             const cv::Mat mat = matOf(image);
             py::gil_scoped_release release;
             return d.detect(mat, frame);
           },
           py::arg("image"), py::arg("frame"), "Detect in `image` ((rows, cols) uint8); returns a FrameDetection.")
      .def_static("toTracks", [](const std::vector<FrameDetection> &frames) {
             return tracksArray(PatternDetector::toTracks(frames));
           }, py::arg("detections"), "Tracks (M, 4) [frame, id, u, v] of a list of FrameDetection.");

  py::class_<KltOptions>(m, "KltOptions", R"doc(
Options of KltTracker (C++ KltOptions, its defaults): max_features, min_distance (px), quality,
block_size (px), window (px), pyramid_levels, forward_backward_px, redetect_fraction, border_px,
gate_sigmas, sigma_px (px), min_depth (m), max_depth (m, inf: none), guided ("off", "auto", "on": the search
along the epipolar segment), guided_min_ncc, ambiguity_margin, guided_levels, min_ncc (the appearance check;
0: none), jump_sigmas (the jump check; 0: none).)doc")
      .def(py::init<>())
      .def_readwrite("max_features", &KltOptions::max_features)
      .def_readwrite("min_distance", &KltOptions::min_distance)
      .def_readwrite("quality", &KltOptions::quality)
      .def_readwrite("block_size", &KltOptions::block_size)
      .def_readwrite("window", &KltOptions::window)
      .def_readwrite("pyramid_levels", &KltOptions::pyramid_levels)
      .def_readwrite("forward_backward_px", &KltOptions::forward_backward_px)
      .def_readwrite("redetect_fraction", &KltOptions::redetect_fraction)
      .def_readwrite("border_px", &KltOptions::border_px)
      .def_readwrite("gate_sigmas", &KltOptions::gate_sigmas)
      .def_readwrite("sigma_px", &KltOptions::sigma_px)
      .def_readwrite("min_depth", &KltOptions::min_depth)
      .def_readwrite("max_depth", &KltOptions::max_depth)
      .def_property(
          "guided", [](const KltOptions &o) { return std::string(toString(o.guided)); },
          [](KltOptions &o, const std::string &s) { o.guided = kltGuidedFromString(s); })
      .def_readwrite("guided_min_ncc", &KltOptions::guided_min_ncc)
      .def_readwrite("ambiguity_margin", &KltOptions::ambiguity_margin)
      .def_readwrite("guided_levels", &KltOptions::guided_levels)
      .def_readwrite("min_ncc", &KltOptions::min_ncc)
      .def_readwrite("jump_sigmas", &KltOptions::jump_sigmas)
      .def("validate", &KltOptions::validate);

  py::class_<KltTracker>(m, "KltTracker", R"doc(
Pyramidal Lucas-Kanade tracks with stable ids (C++ KltTracker). KltTracker(camera, options=KltOptions());
the camera must have its image size.)doc")
      .def(py::init<const CameraModel &, const KltOptions &>(), py::arg("camera"), py::arg("options") = KltOptions())
      .def("track",
           [](KltTracker &t, const Image &image, const py::object &cMp, double sigma_rot, double sigma_trans) {
             const cv::Mat mat = matOf(image);
             KltMotion motion;
             const bool gated = !cMp.is_none();
             if (gated) {
               motion.cMp = toPose(cMp, "cMp");
               motion.sigma_rot = sigma_rot;
               motion.sigma_trans = sigma_trans;
             }
             std::vector<FeatureObservation> out;
             {
               py::gil_scoped_release release;
               out = t.track(mat, gated ? &motion : nullptr);
             }
             return featuresArray(out);
           },
           py::arg("image"), py::arg("cMp") = py::none(), py::arg("sigma_rot") = 0.0, py::arg("sigma_trans") = 0.0,
           R"doc(Track into the next image ((rows, cols) uint8, the camera's size). cMp: (4, 4) pose of the
previous camera in the current one, for the epipolar gate, with its 1-sigma rotation (rad) and
translation (m, per axis); None: no gate. Returns (K, 3) float64 [id, u (px), v (px)].)doc")
      .def_property_readonly("lastStats", [](const KltTracker &t) { return statsOf(t.lastStats()); },
                             "What the last track() did: dict of tracked, lost_flow, lost_fb, lost_border, "
                             "lost_epipolar, detected, guided (continued by the guided search), lost_ambiguous, "
                             "lost_appearance, split_jump.")
      .def("setDepthHint", &KltTracker::setDepthHint, py::arg("id"), py::arg("depth"), py::arg("sigma"),
           "Depth (m) of live feature `id` in its last camera, to narrow its guided search to depth +- 3 sigma; "
           "sigma <= 0 removes it.");

  m.def("trackSequence",
        [](const CameraModel &camera, const YawRig &rig, const MotionLog &motion, const NoiseModel &noise,
           const KltOptions &options, bool gate, const std::optional<std::vector<std::string>> &images) {
          const std::vector<std::string> &files = images ? *images : motion.images;
          SequenceTracks seq;
          {
            py::gil_scoped_release release;
            seq = trackSequence(camera, rig, motion.samples, files, noise, options, gate);
          }
          return py::make_tuple(tracksArray(seq.tracks), statsOf(seq.totals));
        },
        py::arg("camera"), py::arg("rig"), py::arg("motion"), py::arg("noise"), py::arg("options") = KltOptions(),
        py::arg("gate") = true, py::arg("images") = py::none(),
        R"doc(KLT tracks through the images of a motion log (what `yawdepth track` runs): one image per
row (`images`, default motion.images), each step gated by the motion and `noise` unless gate is
False. Returns (tracks (M, 4) [frame, id, u, v] of the features seen in 2 frames or more, totals dict).)doc");

  // ---------------------------------------------------------------- camera calibration
  py::class_<BoardLayout>(m, "BoardLayout", R"doc(
A calibration board: BoardLayout(pattern) with pattern as the CLI's --pattern
('chessboard:COLSxROWS:SQUARE', inner corners, m; or 'apriltag:FAMILY:SIZE'); for an AprilTag grid
set tags_x, tags_y, gap (m) and first_tag_id (C++ defaults: 1, 1, 0, 0; `calibrate-camera`'s
--tag-gap default is a quarter tag: give it here). features() gives (F, 4) [id, X, Y, Z] (m, board frame).)doc")
      .def(py::init([](const std::string &pattern) {
             BoardLayout b;
             b.pattern = PatternSpec::parse(pattern);
             return b;
           }),
           py::arg("pattern"))
      .def_readwrite("tags_x", &BoardLayout::tags_x)
      .def_readwrite("tags_y", &BoardLayout::tags_y)
      .def_readwrite("gap", &BoardLayout::gap)
      .def_readwrite("first_tag_id", &BoardLayout::first_tag_id)
      .def_readwrite("margin", &BoardLayout::margin)
      .def_readwrite("outer_square", &BoardLayout::outer_square)
      .def("features", [](const BoardLayout &b) {
        const auto f = b.features();
        Array a = newArray(static_cast<py::ssize_t>(f.size()), 4);
        auto r = a.mutable_unchecked<2>();
        for (std::size_t i = 0; i < f.size(); ++i) {
          const py::ssize_t k = static_cast<py::ssize_t>(i);
          r(k, 0) = static_cast<double>(f[i].first);
          r(k, 1) = f[i].second.x();
          r(k, 2) = f[i].second.y();
          r(k, 3) = f[i].second.z();
        }
        return a;
      });

  py::class_<CalibrationView>(m, "CalibrationView", "One calibration image's features: name, features (K, 3) "
                              "[id, u (px), v (px)].")
      .def(py::init([](const std::string &name, const py::object &features) {
             CalibrationView v;
             v.name = name;
             const Array a = asRows(features, 3, "features [id, u, v]");
             auto r = a.unchecked<2>();
             for (py::ssize_t k = 0; k < a.shape(0); ++k)
               v.features.push_back({integerOf(r(k, 0), "features", k, "id"), r(k, 1), r(k, 2)});
             return v;
           }),
           py::arg("name"), py::arg("features"))
      .def_readonly("name", &CalibrationView::name)
      .def_property_readonly("features", [](const CalibrationView &v) { return featuresArray(v.features); });

  py::class_<CalibrationDetections>(m, "CalibrationDetections", "detectCalibrationViews()'s result: width, height "
                                    "(px), views (list of CalibrationView), failures, warnings (list of str).")
      .def_readonly("width", &CalibrationDetections::width)
      .def_readonly("height", &CalibrationDetections::height)
      .def_readonly("views", &CalibrationDetections::views)
      .def_readonly("failures", &CalibrationDetections::failures)
      .def_readonly("warnings", &CalibrationDetections::warnings);
  m.def("detectCalibrationViews",
        [](const BoardLayout &board, const std::vector<std::string> &names, const std::vector<Image> &images,
           const DetectorOptions &options) {
          std::vector<cv::Mat> mats;
          for (const Image &i : images)
            mats.push_back(matOf(i));
          py::gil_scoped_release release;
          return detectCalibrationViews(board, names, mats, options);
        },
        py::arg("board"), py::arg("names"), py::arg("images"), py::arg("options") = DetectorOptions(),
        "Detect the board in each image ((rows, cols) uint8; what `calibrate-camera` runs). Raises yawdepth.Error "
        "when the pattern is found in no image or the sizes differ.");

  using Cal = CameraCalibrationOptions;
  py::class_<Cal>(m, "CameraCalibrationOptions", R"doc(
Options of calibrateCamera() (C++ CameraCalibrationOptions, its defaults): fix_aspect_ratio,
fix_principal_point, distortion ('auto', 'k4', 'k5', 'k8', 'fisheye'), try_fisheye, cv_folds,
simpler_within, zero_tangential, drop_outliers, outlier_ratio, outlier_min_px (px), min_views,
min_points_per_view, min_orientation_spread (rad), fit_visp.)doc")
      .def(py::init<>())
      .def_readwrite("fix_aspect_ratio", &Cal::fix_aspect_ratio)
      .def_readwrite("fix_principal_point", &Cal::fix_principal_point)
      .def_property("distortion",
                    [](const Cal &o) -> std::string {
                      switch (o.distortion) {
                      case Cal::Distortion::K4: return "k4";
                      case Cal::Distortion::K5: return "k5";
                      case Cal::Distortion::K8: return "k8";
                      case Cal::Distortion::Fisheye: return "fisheye";
                      default: return "auto";
                      }
                    },
                    [](Cal &o, const std::string &w) {
                      if (w == "auto") o.distortion = Cal::Distortion::Auto;
                      else if (w == "k4") o.distortion = Cal::Distortion::K4;
                      else if (w == "k5") o.distortion = Cal::Distortion::K5;
                      else if (w == "k8") o.distortion = Cal::Distortion::K8;
                      else if (w == "fisheye") o.distortion = Cal::Distortion::Fisheye;
                      else throw Error("distortion '" + w + "': expected auto, k4, k5, k8 or fisheye");
                    })
      .def_readwrite("try_fisheye", &Cal::try_fisheye)
      .def_readwrite("cv_folds", &Cal::cv_folds)
      .def_readwrite("simpler_within", &Cal::simpler_within)
      .def_readwrite("zero_tangential", &Cal::zero_tangential)
      .def_readwrite("drop_outliers", &Cal::drop_outliers)
      .def_readwrite("outlier_ratio", &Cal::outlier_ratio)
      .def_readwrite("outlier_min_px", &Cal::outlier_min_px)
      .def_readwrite("min_views", &Cal::min_views)
      .def_readwrite("min_points_per_view", &Cal::min_points_per_view)
      .def_readwrite("min_orientation_spread", &Cal::min_orientation_spread)
      .def_readwrite("fit_visp", &Cal::fit_visp);

  py::class_<CameraCalibration>(m, "CameraCalibration", R"doc(
calibrateCamera()'s result: camera (CameraModel), rms_px (px), std_devs (12: fx fy u0 v0 k1 k2 p1 p2
k3 k4 k5 k6, px and unitless), intrinsics_covariance (12, 12), views_used, view_rms_px (per view, px),
orientation_spread (rad), coverage (0..1), notes, model_reason, models (list of (name, score_px,
chosen)), uncertainty_grid (6, 8) px; visp_rms_without, visp_rms_with (px).)doc")
      .def_readonly("camera", &CameraCalibration::camera)
      .def_readonly("rms_px", &CameraCalibration::rms_px)
      .def_readonly("std_devs", &CameraCalibration::std_devs)
      .def_property_readonly("intrinsics_covariance",
                             [](const CameraCalibration &c) { return fromEigen(c.intrinsics_covariance); })
      .def_readonly("views_used", &CameraCalibration::views_used)
      .def_property_readonly("view_rms_px", [](const CameraCalibration &c) {
        std::vector<double> v;
        for (const auto &r : c.views)
          v.push_back(r.rms_px);
        return v;
      })
      .def_readonly("orientation_spread", &CameraCalibration::orientation_spread)
      .def_readonly("coverage", &CameraCalibration::coverage)
      .def_readonly("notes", &CameraCalibration::notes)
      .def_readonly("model_reason", &CameraCalibration::model_reason)
      .def_property_readonly("models", [](const CameraCalibration &c) {
        py::list l;
        for (const auto &s : c.models)
          l.append(py::make_tuple(s.name, s.score_px, s.chosen));
        return l;
      })
      .def_property_readonly("uncertainty_grid", [](const CameraCalibration &c) {
        Array a = newArray(6, 8);
        for (std::size_t i = 0; i < c.uncertainty_grid.size() && i < 48; ++i)
          a.mutable_data()[i] = c.uncertainty_grid[i];
        return a;
      })
      .def_readonly("visp_rms_without", &CameraCalibration::visp_rms_without)
      .def_readonly("visp_rms_with", &CameraCalibration::visp_rms_with);
  m.def("calibrateCamera",
        [](const BoardLayout &board, const std::vector<CalibrationView> &views, int width, int height,
           const Cal &options) {
          py::gil_scoped_release release;
          return calibrateCamera(board, views, width, height, options);
        },
        py::arg("board"), py::arg("views"), py::arg("width"), py::arg("height"), py::arg("options") = Cal(),
        "Calibrate from detected views (what `calibrate-camera` runs); raises yawdepth.Error for too few or "
        "degenerate views.");
  m.def("projectionUncertainty", &projectionUncertainty, py::arg("calibration"), py::arg("u"), py::arg("v"),
        "How uncertain the calibrated projection of pixel (u, v)'s ray is (px, 1 sigma).");
  m.def("saveVispCameraXml", [](const std::string &path, const CameraCalibration &c, const std::optional<std::string> &name) {
          if (name)
            saveVispCameraXml(path, c, *name);
          else
            saveVispCameraXml(path, c); // the C++ default name
        }, py::arg("path"), py::arg("calibration"), py::arg("camera_name") = py::none(),
        "Write the ViSP camera XML (models without and with distortion) of a calibration.");

  // ---------------------------------------------------------------- yaw rig calibration
  py::class_<RigView>(m, "RigView", R"doc(
One image of the yaw-rig calibration: RigView(row, features): row, its motion row (6 or 8 numbers,
as MotionLog.samples; yaw = the reading); features (K, 3) [id, u (px), v (px)] of the board.)doc")
      .def(py::init([](const py::object &row, const py::object &features) {
             RigView v;
             v.sample = sampleOf(row);
             const Array a = asRows(features, 3, "features [id, u, v]");
             auto r = a.unchecked<2>();
             for (py::ssize_t k = 0; k < a.shape(0); ++k)
               v.features.push_back({integerOf(r(k, 0), "features", k, "id"), r(k, 1), r(k, 2)});
             return v;
           }),
           py::arg("row"), py::arg("features"))
      .def_property_readonly("row", [](const RigView &v) { return motionArray({v.sample}).reshape({-1}); })
      .def_property_readonly("features", [](const RigView &v) { return featuresArray(v.features); });
  py::class_<RigCalibrationOptions>(m, "RigCalibrationOptions", R"doc(
Options of calibrateRig() (C++ RigCalibrationOptions, its defaults): initial_offset (3,) m with
use_initial_offset, initial_yaw_offset (rad), board_square, estimate_axis, min_yaw_span (rad),
min_distinct_yaws, min_baseline (m), min_points_per_view, max_rms_px (px), max_offset (m),
max_offset_sigma (m), check_board_scale.)doc")
      .def(py::init<>())
      .def_property("initial_offset", [](const RigCalibrationOptions &o) { return fromEigen(o.initial_offset); },
                    [](RigCalibrationOptions &o, const py::object &v) {
                      const Array a = Array::ensure(v);
                      if (!a || a.size() != 3)
                        throw Error("initial_offset: expected 3 numbers (m)");
                      o.initial_offset = Eigen::Vector3d(a.data()[0], a.data()[1], a.data()[2]);
                    })
      .def_readwrite("use_initial_offset", &RigCalibrationOptions::use_initial_offset)
      .def_readwrite("initial_yaw_offset", &RigCalibrationOptions::initial_yaw_offset)
      .def_readwrite("board_square", &RigCalibrationOptions::board_square)
      .def_readwrite("estimate_axis", &RigCalibrationOptions::estimate_axis)
      .def_readwrite("min_yaw_span", &RigCalibrationOptions::min_yaw_span)
      .def_readwrite("min_distinct_yaws", &RigCalibrationOptions::min_distinct_yaws)
      .def_readwrite("min_baseline", &RigCalibrationOptions::min_baseline)
      .def_readwrite("min_points_per_view", &RigCalibrationOptions::min_points_per_view)
      .def_readwrite("max_rms_px", &RigCalibrationOptions::max_rms_px)
      .def_readwrite("max_offset", &RigCalibrationOptions::max_offset)
      .def_readwrite("max_offset_sigma", &RigCalibrationOptions::max_offset_sigma)
      .def_readwrite("check_board_scale", &RigCalibrationOptions::check_board_scale);
  py::class_<RigCalibration>(m, "RigCalibration", R"doc(
calibrateRig()'s result: camera_offset (3,) m and camera_offset_sigma, yaw_axis (3,) and
yaw_axis_sigma, yaw_offset (rad, true yaw = reading + yaw_offset) and yaw_offset_sigma, rms_px (px),
view_rms_px, views, points, yaw_span (rad), distinct_yaws, baseline (m). rigCalibrationYaml() gives
its rig file.)doc")
      .def_property_readonly("camera_offset", [](const RigCalibration &c) { return fromEigen(c.camera_offset).reshape({3}); })
      .def_property_readonly("camera_offset_sigma",
                             [](const RigCalibration &c) { return fromEigen(c.camera_offset_sigma).reshape({3}); })
      .def_property_readonly("yaw_axis", [](const RigCalibration &c) { return fromEigen(c.yaw_axis).reshape({3}); })
      .def_property_readonly("yaw_axis_sigma", [](const RigCalibration &c) { return fromEigen(c.yaw_axis_sigma).reshape({3}); })
      .def_readonly("yaw_offset", &RigCalibration::yaw_offset)
      .def_readonly("yaw_offset_sigma", &RigCalibration::yaw_offset_sigma)
      .def_readonly("rms_px", &RigCalibration::rms_px)
      .def_readonly("view_rms_px", &RigCalibration::view_rms_px)
      .def_readonly("views", &RigCalibration::views)
      .def_readonly("points", &RigCalibration::points)
      .def_readonly("yaw_span", &RigCalibration::yaw_span)
      .def_readonly("distinct_yaws", &RigCalibration::distinct_yaws)
      .def_readonly("baseline", &RigCalibration::baseline);
  m.def("calibrateRig",
        [](const CameraModel &camera, const BoardLayout &board, const std::vector<RigView> &views,
           const RigCalibrationOptions &options) {
          py::gil_scoped_release release;
          return calibrateRig(camera, board, views, options);
        },
        py::arg("camera"), py::arg("board"), py::arg("views"), py::arg("options") = RigCalibrationOptions(),
        "The yaw rig from views of a static board (what `calibrate-rig` runs); raises yawdepth.Error for too few "
        "views, too small a yaw span or a failed fit.");
  m.def("rigCalibrationYaml", &rigCalibrationYaml, py::arg("calibration"),
        "The rig file text (YAML) of a rig calibration, as calibrate-rig writes it.");

  // ---------------------------------------------------------------- hand-eye calibration
  py::class_<HandEyeView>(m, "HandEyeView", R"doc(
One hand-eye image: HandEyeView(rMe, features, name): rMe (4, 4) the hand's pose in the robot base
when the image was taken (m); features (K, 3) [id, u (px), v (px)] of the board; name for messages.)doc")
      .def(py::init([](const py::object &rMe, const py::object &features, const std::string &name) {
             HandEyeView v;
             v.rMe = toPose(rMe, "rMe");
             const Array a = asRows(features, 3, "features [id, u, v]");
             auto r = a.unchecked<2>();
             for (py::ssize_t k = 0; k < a.shape(0); ++k)
               v.features.push_back({integerOf(r(k, 0), "features", k, "id"), r(k, 1), r(k, 2)});
             v.name = name;
             return v;
           }),
           py::arg("rMe"), py::arg("features"), py::arg("name") = std::string())
      .def_property_readonly("rMe", [](const HandEyeView &v) { return fromPose(v.rMe); })
      .def_property_readonly("features", [](const HandEyeView &v) { return featuresArray(v.features); })
      .def_readonly("name", &HandEyeView::name);
  py::class_<HandEyeOptions>(m, "HandEyeOptions", R"doc(
Options of calibrateHandEye() (C++ HandEyeOptions, its defaults): setup ('eye-in-hand' or
'eye-to-hand'), min_points_per_view, max_rms_px (px), sigma_px (px), sigma_pose_translation (m),
sigma_pose_rotation (rad), max_pose_correction_sigmas, check_board_scale.)doc")
      .def(py::init<>())
      .def_property("setup",
                    [](const HandEyeOptions &o) {
                      return std::string(o.setup == HandEyeSetup::EyeInHand ? "eye-in-hand" : "eye-to-hand");
                    },
                    [](HandEyeOptions &o, const std::string &w) { o.setup = handEyeSetupFromString(w); })
      .def_readwrite("min_points_per_view", &HandEyeOptions::min_points_per_view)
      .def_readwrite("max_rms_px", &HandEyeOptions::max_rms_px)
      .def_readwrite("sigma_px", &HandEyeOptions::sigma_px)
      .def_readwrite("sigma_pose_translation", &HandEyeOptions::sigma_pose_translation)
      .def_readwrite("sigma_pose_rotation", &HandEyeOptions::sigma_pose_rotation)
      .def_readwrite("max_pose_correction_sigmas", &HandEyeOptions::max_pose_correction_sigmas)
      .def_readwrite("check_board_scale", &HandEyeOptions::check_board_scale);
  py::class_<HandEyeCalibration>(m, "HandEyeCalibration", R"doc(
calibrateHandEye()'s result: camera_pose (4, 4) eMc (eye-in-hand) or rMc (eye-to-hand), target_pose
(4, 4) rMo or eMo, camera_pose_sigma and target_pose_sigma (6,) [tx, ty, tz (m), tux, tuy, tuz (rad)],
rms_px, initial_rms_px (px), views, points, view_rms_px, view_names, skipped,
pose_correction_mm, pose_correction_deg. handEyeRigYaml() gives its rig file.)doc")
      .def_property_readonly("camera_pose", [](const HandEyeCalibration &c) { return fromPose(c.camera_pose); })
      .def_property_readonly("target_pose", [](const HandEyeCalibration &c) { return fromPose(c.target_pose); })
      .def_property_readonly("camera_pose_sigma",
                             [](const HandEyeCalibration &c) { return fromEigen(c.camera_pose_sigma).reshape({6}); })
      .def_property_readonly("target_pose_sigma",
                             [](const HandEyeCalibration &c) { return fromEigen(c.target_pose_sigma).reshape({6}); })
      .def_readonly("rms_px", &HandEyeCalibration::rms_px)
      .def_readonly("initial_rms_px", &HandEyeCalibration::initial_rms_px)
      .def_readonly("views", &HandEyeCalibration::views)
      .def_readonly("points", &HandEyeCalibration::points)
      .def_readonly("view_rms_px", &HandEyeCalibration::view_rms_px)
      .def_readonly("view_names", &HandEyeCalibration::view_names)
      .def_readonly("skipped", &HandEyeCalibration::skipped)
      .def_readonly("pose_correction_mm", &HandEyeCalibration::pose_correction_mm)
      .def_readonly("pose_correction_deg", &HandEyeCalibration::pose_correction_deg);
  m.def("calibrateHandEye",
        [](const CameraModel &camera, const BoardLayout &board, const std::vector<HandEyeView> &views,
           const HandEyeOptions &options) {
          py::gil_scoped_release release;
          return calibrateHandEye(camera, board, views, options);
        },
        py::arg("camera"), py::arg("board"), py::arg("views"), py::arg("options") = HandEyeOptions(),
        "Hand-eye calibration (what `calibrate-rig --hand-eye` runs); raises yawdepth.Error for too few usable "
        "views, degenerate rotations or a failed fit.");
  m.def("handEyeRigYaml", &handEyeRigYaml, py::arg("calibration"),
        "The rig file text (YAML, camera_pose and its sigma) of a hand-eye calibration, as calibrate-rig writes it.");

  // ---------------------------------------------------------------- error analysis
  py::class_<ErrorAnalysisCase>(m, "ErrorAnalysisCase", R"doc(
One case of the error analysis (m, rad, px; C++ defaults): yaw (rad, 0 front view), depth (m),
u_offset (px), dz (m), kx (px), delta_dz (m), delta_yaw (rad), delta_u (px), delta_du (px).)doc")
      .def(py::init<>())
      .def_readwrite("yaw", &ErrorAnalysisCase::yaw)
      .def_readwrite("depth", &ErrorAnalysisCase::depth)
      .def_readwrite("u_offset", &ErrorAnalysisCase::u_offset)
      .def_readwrite("dz", &ErrorAnalysisCase::dz)
      .def_readwrite("kx", &ErrorAnalysisCase::kx)
      .def_readwrite("delta_dz", &ErrorAnalysisCase::delta_dz)
      .def_readwrite("delta_yaw", &ErrorAnalysisCase::delta_yaw)
      .def_readwrite("delta_u", &ErrorAnalysisCase::delta_u)
      .def_readwrite("delta_du", &ErrorAnalysisCase::delta_du)
      .def("validate", &ErrorAnalysisCase::validate);
  py::class_<DepthErrorTerms>(m, "DepthErrorTerms", "First-order relative depth error terms (dimensionless; "
                              "parallax_px in px): parallax_px, odometry, yaw, pixel, parallax, total.")
      .def_readonly("parallax_px", &DepthErrorTerms::parallax_px)
      .def_readonly("odometry", &DepthErrorTerms::odometry)
      .def_readonly("yaw", &DepthErrorTerms::yaw)
      .def_readonly("pixel", &DepthErrorTerms::pixel)
      .def_readonly("parallax", &DepthErrorTerms::parallax)
      .def_readonly("total", &DepthErrorTerms::total);
  py::class_<MonteCarloDepthError>(m, "MonteCarloDepthError", "rms_relative, median_abs_relative, bias_relative, samples.")
      .def_readonly("rms_relative", &MonteCarloDepthError::rms_relative)
      .def_readonly("median_abs_relative", &MonteCarloDepthError::median_abs_relative)
      .def_readonly("bias_relative", &MonteCarloDepthError::bias_relative)
      .def_readonly("samples", &MonteCarloDepthError::samples);
  py::class_<PaperErrorRow>(m, "PaperErrorRow", "A row of the paper's Section 4 table: view, input, lateral_depth_error.")
      .def_readonly("view", &PaperErrorRow::view)
      .def_readonly("input", &PaperErrorRow::input)
      .def_readonly("lateral_depth_error", &PaperErrorRow::lateral_depth_error);
  m.def("firstOrderDepthError", &firstOrderDepthError, py::arg("c"), "First-order terms of eqs. (9)-(14).");
  m.def("firstOrderDepthSigma", &firstOrderDepthSigma, py::arg("c"),
        "Statistical first-order relative depth error (1 sigma).");
  m.def("lateralRelativeError", &lateralRelativeError, py::arg("delta_u"), py::arg("kx"), py::arg("u_offset"),
        py::arg("depth_relative_error"), "Lateral error, eq. (17).");
  m.def("monteCarloDepthError",
        [](const ErrorAnalysisCase &c, int samples, std::uint64_t seed) {
          py::gil_scoped_release release;
          return monteCarloDepthError(c, samples, seed);
        },
        py::arg("c"), py::arg("samples"), py::arg("seed") = 1, "Monte Carlo of eq. (9) (reproducible by seed).");
  m.def("paperErrorCases", &paperErrorCases, "The cases of the paper's Section 4 table.");
  m.def("formatPaperTerm", &formatPaperTerm, py::arg("v"), "A term as the paper prints it.");
  m.def("formatPercent", &formatPercent, py::arg("v"), "A relative error as a percentage with two decimals.");
}

} // namespace yawdepth::python
