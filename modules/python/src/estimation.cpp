// estimatePoints() and its options: NoiseModel, GateOptions, ResidualCheckOptions, PipelineOptions.
// Every default is the C++ struct's (the classes are the structs; a default-constructed one is
// what the command line starts from).
#include "common.h"

#include <yawdepth/error.h>
#include <yawdepth/pipeline/pipeline.h>

namespace yawdepth::python {

namespace {

/*! What estimatePoints() returns to Python: the rows (ids with their estimates) and the rest of
    the PipelineResult. */
struct Estimate {
  std::vector<PointRow> rows;
  PipelineResult result;
};

} // namespace

void bindEstimation(py::module_ &m)
{
  py::class_<NoiseModel>(m, "NoiseModel", R"doc(
Noise of the inputs (1-sigma): sigma_px (px, per pixel coordinate), sigma_odom (m per increment per
axis), sigma_heading (rad per increment, planar logs), sigma_yaw (rad per yaw reading), sigma_rot
(rad per increment per axis, 6-DoF logs), odom_per_metre (m/m), rot_per_radian (rad/rad),
rot_per_metre (rad/m), motion_noise ('increment' or 'absolute'), pixel_correlation (the tracker's
errors' AR(1) correlation from one image of a track to the next, 0 to 0.99; methods 'window' and 'refine'). NoiseModel() has the C++ defaults
(the command line's).)doc")
      .def(py::init<>())
      .def_readwrite("sigma_px", &NoiseModel::sigma_px)
      .def_readwrite("sigma_odom", &NoiseModel::sigma_odom)
      .def_readwrite("sigma_heading", &NoiseModel::sigma_heading)
      .def_readwrite("sigma_yaw", &NoiseModel::sigma_yaw)
      .def_readwrite("sigma_rot", &NoiseModel::sigma_rot)
      .def_readwrite("odom_per_metre", &NoiseModel::odom_per_metre)
      .def_readwrite("rot_per_radian", &NoiseModel::rot_per_radian)
      .def_readwrite("rot_per_metre", &NoiseModel::rot_per_metre)
      .def_readwrite("pixel_correlation", &NoiseModel::pixel_correlation)
      .def_property("motion_noise", [](const NoiseModel &n) { return std::string(toString(n.motion_noise)); },
                    [](NoiseModel &n, const std::string &w) { n.motion_noise = motionNoiseFromString(w); },
                    "'increment' (odometry: errors accumulate) or 'absolute' (kinematics: per pose).")
      .def("validate", &NoiseModel::validate, "Raise yawdepth.Error unless every sigma is finite and >= 0.");

  py::class_<GateOptions>(m, "GateOptions", R"doc(
Gates: min_baseline (m; less camera translation is 'no_motion'), min_parallax_px (px; less parallax
is 'degenerate'). GateOptions() has the C++ defaults.)doc")
      .def(py::init<>())
      .def_readwrite("min_baseline", &GateOptions::min_baseline)
      .def_readwrite("min_parallax_px", &GateOptions::min_parallax_px)
      .def("validate", &GateOptions::validate);

  py::class_<ResidualCheckOptions>(m, "ResidualCheckOptions",
                                   "The residual check (C++ ResidualCheckOptions; `enabled` is --residual-check on).")
      .def(py::init<>())
      .def_readwrite("enabled", &ResidualCheckOptions::enabled)
      .def_readwrite("gate_probability", &ResidualCheckOptions::gate_probability)
      .def_readwrite("scale_sigma", &ResidualCheckOptions::scale_sigma)
      .def_readwrite("min_tracks", &ResidualCheckOptions::min_tracks)
      .def_readwrite("correlated", &ResidualCheckOptions::correlated)
      .def_readwrite("reestimate_noise", &ResidualCheckOptions::reestimate_noise);

  py::class_<PipelineOptions>(m, "PipelineOptions", R"doc(
Options of estimatePoints() (C++ PipelineOptions, defaults from C++): method ('paper', 'exact',
'fused', 'window', 'refine'), noise (NoiseModel), gates (GateOptions), robust_threshold_px and
outlier_threshold_px (px; window, refine), window (frames), threads (refine), drop_unusable,
residual_check (ResidualCheckOptions), max_depth_sigma (sigma_Z / Z above which an ok point is
'degenerate'; 0: no gate).)doc")
      .def(py::init<>())
      .def_property("method", [](const PipelineOptions &o) { return std::string(toString(o.method)); },
                    [](PipelineOptions &o, const std::string &w) { o.method = methodFromString(w); })
      .def_readwrite("noise", &PipelineOptions::noise)
      .def_readwrite("gates", &PipelineOptions::gates)
      .def_readwrite("robust_threshold_px", &PipelineOptions::robust_threshold_px)
      .def_readwrite("outlier_threshold_px", &PipelineOptions::outlier_threshold_px)
      .def_readwrite("window", &PipelineOptions::window)
      .def_readwrite("threads", &PipelineOptions::threads)
      .def_readwrite("drop_unusable", &PipelineOptions::drop_unusable)
      .def_readwrite("residual_check", &PipelineOptions::residual_check)
      .def_readwrite("max_depth_sigma", &PipelineOptions::max_depth_sigma)
      .def("validate", &PipelineOptions::validate, "Raise yawdepth.Error for options that cannot give an answer.")
      .def("__copy__", [](const PipelineOptions &o) { return o; })
      .def("__deepcopy__", [](const PipelineOptions &o, const py::dict &) { return o; }, py::arg("memo"));

  m.def("methodAvailable", [](const std::string &w) { return methodAvailable(methodFromString(w)); }, py::arg("method"),
        "Whether this build has the method (refine needs Ceres).");
  m.def("bestMethod", [] { return std::string(toString(bestMethod())); },
        "The most accurate method this build has: 'refine' with Ceres, else 'fused'.");
  m.def("noiseForMotionLog", &noiseForMotionLog, py::arg("noise"), py::arg("six_dof"), py::arg("yaw_column"),
        py::arg("sigma_yaw_given"),
        "The noise model for a log: a 6-DoF log without a yaw column gets sigma_yaw 0 unless sigma_yaw_given.");

  py::class_<Estimate>(m, "Estimate", R"doc(
What estimatePoints() returns.
  points: structured array, one row per track (tracks by id), the points CSV's columns:
          id (int64), frame (int64, the track's last observed frame), x, y, z (float64, m, the point
          in the vision frame at `frame`), xc, yc, zc (float64, m, in the camera frame at `frame`),
          sigma_zc (float64, m, 1-sigma of zc), status (str: 'ok', 'degenerate', 'behind',
          'no_motion', 'too_few_frames', 'undistort_failed', 'unavailable', 'inconsistent');
          the numbers are NaN unless status is 'ok'.
  c_cov: (P, 3, 3) float64, covariance of (xc, yc, zc) (m^2), NaN unless ok.
  outliers: list of P bool arrays, per track and observation (in frame order): rejected or unusable.
  motion: the motion as estimated (refine) or as given, as MotionLog.samples.
  warnings: list of str, one line each (what the command line prints as warnings).
  s0, outlier_share, tracks_used, mistake: the whole log against the noise model (Consistency).
  noise_scale, variance_factor, sigma_scale, inconsistent: the residual check's findings.)doc")
      .def_property_readonly("points", [](const Estimate &e) { return pointsArray(e.rows); })
      .def_property_readonly("c_cov", [](const Estimate &e) {
        py::array_t<double> a({static_cast<py::ssize_t>(e.rows.size()), py::ssize_t(3), py::ssize_t(3)});
        auto r = a.mutable_unchecked<3>();
        for (std::size_t i = 0; i < e.rows.size(); ++i)
          for (int j = 0; j < 3; ++j)
            for (int k = 0; k < 3; ++k)
              r(static_cast<py::ssize_t>(i), j, k) = e.rows[i].estimate.c_cov(j, k);
        return a;
      })
      .def_property_readonly("outliers", [](const Estimate &e) {
        py::list out;
        for (const std::vector<bool> &o : e.result.outliers) {
          py::array_t<bool> a(static_cast<py::ssize_t>(o.size()));
          for (std::size_t k = 0; k < o.size(); ++k)
            a.mutable_at(static_cast<py::ssize_t>(k)) = o[k];
          out.append(a);
        }
        return out;
      })
      .def_property_readonly("motion", [](const Estimate &e) { return motionArray(e.result.motion); })
      .def_property_readonly("warnings", [](const Estimate &e) { return e.result.warnings; })
      .def_property_readonly("s0", [](const Estimate &e) { return e.result.consistency.s0; })
      .def_property_readonly("outlier_share", [](const Estimate &e) { return e.result.consistency.outlier_share; })
      .def_property_readonly("tracks_used", [](const Estimate &e) { return e.result.consistency.tracks_used; })
      .def_property_readonly("mistake", [](const Estimate &e) { return e.result.consistency.mistake; })
      .def_property_readonly("noise_scale", [](const Estimate &e) { return e.result.residuals.noise_scale; })
      .def_property_readonly("variance_factor", [](const Estimate &e) { return e.result.residuals.variance_factor; })
      .def_property_readonly("sigma_scale", [](const Estimate &e) { return e.result.residuals.sigma_scale; })
      .def_property_readonly("inconsistent", [](const Estimate &e) { return e.result.residuals.inconsistent; })
      .def("__len__", [](const Estimate &e) { return e.rows.size(); });

  // The call itself (yawdepth.estimatePoints in __init__.py turns keywords into PipelineOptions).
  m.def("_estimatePoints",
        [](const CameraModel &camera, const YawRig &rig, const py::object &motion, const py::object &tracks,
           PipelineOptions options, bool sigma_yaw_given) {
          MotionLog converted; // an array given: its log; a MotionLog: used where it is, not copied
          const bool is_log = py::isinstance<MotionLog>(motion);
          if (!is_log)
            converted = motionLogOf(motion);
          const MotionLog &log = is_log ? motion.cast<const MotionLog &>() : converted;
          const std::vector<Track> t = tracksOf(tracks);
          options.noise = noiseForMotionLog(options.noise, !log.samples.empty() && log.samples.front().six_dof,
                                            log.yaw_column, sigma_yaw_given);
          auto e = std::make_unique<Estimate>();
          {
            py::gil_scoped_release release; // another Python thread runs while the method does
            e->result = estimatePoints(camera, rig, log.samples, t, options);
          }
          e->rows.reserve(t.size());
          for (std::size_t i = 0; i < t.size(); ++i)
            e->rows.push_back({t[i].id, e->result.points[i]});
          return e;
        },
        py::arg("camera"), py::arg("rig"), py::arg("motion"), py::arg("tracks"), py::arg("options"),
        py::arg("sigma_yaw_given"));
  m.def("_writeEstimateCsv", [](const std::string &path, const Estimate &e) { writePointsCsv(path, e.rows); },
        py::arg("path"), py::arg("estimate"));
}

} // namespace yawdepth::python
