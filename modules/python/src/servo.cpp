// The streaming form: DepthProvider (servo) and StreamEstimator (window / fused frame by frame),
// and PointEstimate. Features per period: a dict {id: (u, v)} or an (K, 3) array [id, u, v] (px).
#include "common.h"

#include <yawdepth/error.h>
#include <yawdepth/servo/depth_provider.h>
#include <yawdepth/window/stream_estimator.h>

namespace yawdepth::python {

namespace {

/*! Features of one period as (id, u, v) triples, from a dict {id: (u, v)} or an (K, 3) array. */
std::vector<FeatureObservation> featuresOf(const py::handle &points)
{
  std::vector<FeatureObservation> out;
  if (py::isinstance<py::dict>(points)) {
    const py::dict d = py::reinterpret_borrow<py::dict>(points);
    out.reserve(d.size());
    for (const auto &kv : d) {
      const py::sequence uv = py::reinterpret_borrow<py::sequence>(kv.second);
      if (py::len(uv) != 2)
        throw Error("features: each value must be (u, v) in px");
      out.push_back({kv.first.cast<long>(), uv[0].cast<double>(), uv[1].cast<double>()});
    }
    return out;
  }
  const Array a = asRows(points, 3, "features [id, u, v]");
  auto r = a.unchecked<2>();
  out.reserve(static_cast<std::size_t>(a.shape(0)));
  for (py::ssize_t k = 0; k < a.shape(0); ++k)
    out.push_back({integerOf(r(k, 0), "features", k, "id"), r(k, 1), r(k, 2)});
  return out;
}

std::vector<std::pair<long, vpImagePoint>> imagePoints(const std::vector<FeatureObservation> &f)
{
  std::vector<std::pair<long, vpImagePoint>> out;
  out.reserve(f.size());
  for (const FeatureObservation &o : f)
    out.emplace_back(o.id, vpImagePoint(o.v, o.u)); // vpImagePoint(i = row = v, j = column = u)
  return out;
}

} // namespace

void bindServo(py::module_ &m)
{
  m.def("wMv", [](const py::object &row) { return fromPose(wMv(sampleOf(row))); }, py::arg("row"),
        "(4, 4) float64: the vision frame's pose in the world for a motion row (6 or 8 numbers, as MotionLog.samples).");
  m.def("wMc", [](const YawRig &rig, const py::object &row) { return fromPose(wMc(rig, sampleOf(row))); },
        py::arg("rig"), py::arg("row"), "(4, 4) float64: the camera's pose in the world for a motion row.");
  m.def("curMprev", [](const YawRig &rig, const py::object &prev, const py::object &cur) {
          return fromPose(curMprev(rig, sampleOf(prev), sampleOf(cur)));
        }, py::arg("rig"), py::arg("prev"), py::arg("cur"),
        "(4, 4) float64: the camera motion between two motion rows, cur_P = curMprev @ prev_P.");

  py::class_<PointEstimate>(m, "PointEstimate", R"doc(
One feature's estimate: status (str), frame, c_P (3,) float64 (m, camera frame at `frame`), v_P (3,)
(m, vision frame at `frame`), c_cov (3, 3) (m^2), sigmaZ (m), parallax_px (px); numbers NaN unless ok.)doc")
      .def_property_readonly("status", [](const PointEstimate &e) { return std::string(toString(e.status)); })
      .def_readonly("frame", &PointEstimate::frame)
      .def_property_readonly("c_P", [](const PointEstimate &e) { return fromEigen(e.c_P).reshape({3}); })
      .def_property_readonly("v_P", [](const PointEstimate &e) { return fromEigen(e.v_P).reshape({3}); })
      .def_property_readonly("c_cov", [](const PointEstimate &e) { return fromEigen(e.c_cov); })
      .def_property_readonly("sigmaZ", &PointEstimate::sigmaZ)
      .def_readonly("parallax_px", &PointEstimate::parallax_px)
      .def_property_readonly("ok", &PointEstimate::ok);

  py::class_<FeatureDepth>(m, "FeatureDepth", R"doc(
DepthProvider.info(id): depth (m, what the servo should use), sigma (m), converged (bool), status (str),
estimate and estimate_sigma (m, NaN unless ok), revocations.)doc")
      .def_readonly("id", &FeatureDepth::id)
      .def_readonly("depth", &FeatureDepth::depth)
      .def_readonly("sigma", &FeatureDepth::sigma)
      .def_readonly("converged", &FeatureDepth::converged)
      .def_property_readonly("status", [](const FeatureDepth &f) { return std::string(toString(f.status)); })
      .def_readonly("estimate", &FeatureDepth::estimate)
      .def_readonly("estimate_sigma", &FeatureDepth::estimate_sigma)
      .def_readonly("revocations", &FeatureDepth::revocations);

  py::class_<DepthProviderOptions>(m, "DepthProviderOptions", R"doc(
Options of DepthProvider (C++ DepthProviderOptions, its defaults): prior_depth (m),
prior_relative_sigma, converged_relative_sigma, release_factor, revoke_sigmas, confirm_periods,
min_depth, max_depth (m), min_translation (m), max_skipped_periods, noise (NoiseModel: servoNoiseModel()),
initial_depth (m), max_missing_frames, method ('window' or 'fused'), window (frames).)doc")
      .def(py::init<>())
      .def_readwrite("prior_depth", &DepthProviderOptions::prior_depth)
      .def_readwrite("prior_relative_sigma", &DepthProviderOptions::prior_relative_sigma)
      .def_readwrite("converged_relative_sigma", &DepthProviderOptions::converged_relative_sigma)
      .def_readwrite("release_factor", &DepthProviderOptions::release_factor)
      .def_readwrite("revoke_sigmas", &DepthProviderOptions::revoke_sigmas)
      .def_readwrite("confirm_periods", &DepthProviderOptions::confirm_periods)
      .def_readwrite("min_depth", &DepthProviderOptions::min_depth)
      .def_readwrite("max_depth", &DepthProviderOptions::max_depth)
      .def_readwrite("min_translation", &DepthProviderOptions::min_translation)
      .def_readwrite("max_skipped_periods", &DepthProviderOptions::max_skipped_periods)
      .def_readwrite("noise", &DepthProviderOptions::noise)
      .def_readwrite("initial_depth", &DepthProviderOptions::initial_depth)
      .def_readwrite("max_missing_frames", &DepthProviderOptions::max_missing_frames)
      .def_property("method", [](const DepthProviderOptions &o) { return std::string(toString(o.method)); },
                    [](DepthProviderOptions &o, const std::string &w) { o.method = streamMethodFromString(w); })
      .def_readwrite("window", &DepthProviderOptions::window)
      .def("validate", &DepthProviderOptions::validate);

  py::class_<DepthProvider>(m, "DepthProvider", R"doc(
Depth of each tracked feature for a visual servo, one update() per control period (C++
yawdepth::DepthProvider; docs/python.md). DepthProvider(camera, rig, options=DepthProviderOptions()).)doc")
      .def(py::init<const CameraModel &, const YawRig &, const DepthProviderOptions &>(), py::arg("camera"),
           py::arg("rig"), py::arg("options") = DepthProviderOptions())
      .def("update",
           [](DepthProvider &p, const py::object &wMv, const py::object &points, double yaw) {
             const vpHomogeneousMatrix M = toPose(wMv, "wMv");
             const auto pts = imagePoints(featuresOf(points));
             py::gil_scoped_release release;
             p.update(M, pts, yaw);
           },
           py::arg("wMv"), py::arg("points"), py::arg("yaw") = 0.0,
           R"doc(One control period: wMv (4, 4) float64, the pose of the vision frame in a fixed world
frame (m; e.g. the camera's own pose with an identity camera_pose rig); points: dict {id: (u, v)} or
(K, 3) float64 [id, u (px), v (px)], the observed (distorted) pixels; yaw: pan reading (rad), else 0.
Raises yawdepth.Error for a non-finite pose or a repeated id.)doc")
      .def("updateOdometry",
           [](DepthProvider &p, const py::object &odometry, const py::object &points) {
             const MotionSample s = sampleOf(odometry);
             const auto pts = imagePoints(featuresOf(points));
             py::gil_scoped_release release;
             p.update(s, pts);
           },
           py::arg("odometry"), py::arg("points"),
           "One control period from an odometry row: 6 [frame, x, y, z, heading, yaw] or 8 [frame, tx, ty, "
           "tz, tux, tuy, tuz, yaw] numbers (m, rad; frame ignored), points as update().")
      .def("depth", &DepthProvider::depth, py::arg("id"), "Depth to use for feature `id` (m), in [min_depth, max_depth].")
      .def("sigma", &DepthProvider::sigma, py::arg("id"), "1-sigma of depth(id) (m).")
      .def("status", [](const DepthProvider &p, long id) { return std::string(toString(p.status(id))); },
           py::arg("id"), "The estimator's status word for `id`.")
      .def("converged", &DepthProvider::converged, py::arg("id"), "Whether depth(id) is the estimate (else the prior).")
      .def("info", &DepthProvider::info, py::arg("id"), "FeatureDepth of `id`.")
      .def("estimate", &DepthProvider::estimate, py::arg("id"), "PointEstimate of `id` at the current frame.")
      .def("setPrior", &DepthProvider::setPrior, py::arg("id"), py::arg("Z"), "A prior depth for one feature (m, > 0).")
      .def_property_readonly("periods", &DepthProvider::periods, "Control periods so far.")
      .def_property_readonly("estimatorFrames", &DepthProvider::estimatorFrames, "Frames fed to the estimator.");

  py::class_<StreamOptions>(m, "StreamOptions", R"doc(
Options of StreamEstimator: method ('window' or 'fused'); noise and gates (the call's one noise
model); window (frames), robust_threshold_px, outlier_threshold_px for window; prior_depth (m) for
both; max_missing_frames for fused. Defaults from C++ (StreamOptions).)doc")
      .def(py::init<>())
      .def_property("method", [](const StreamOptions &o) { return std::string(toString(o.method)); },
                    [](StreamOptions &o, const std::string &w) { o.method = streamMethodFromString(w); })
      .def_readwrite("noise", &StreamOptions::noise)
      .def_readwrite("gates", &StreamOptions::gates)
      .def_readwrite("window", &StreamOptions::window)
      .def_readwrite("robust_threshold_px", &StreamOptions::robust_threshold_px)
      .def_readwrite("outlier_threshold_px", &StreamOptions::outlier_threshold_px)
      .def_readwrite("prior_depth", &StreamOptions::prior_depth)
      .def_readwrite("max_missing_frames", &StreamOptions::max_missing_frames);

  py::class_<StreamEstimator>(m, "StreamEstimator", R"doc(
Frames in one at a time, estimates out (window or fused; C++ yawdepth::StreamEstimator).
StreamEstimator(camera, rig, options=StreamOptions()).)doc")
      .def(py::init<const CameraModel &, const YawRig &, const StreamOptions &>(), py::arg("camera"), py::arg("rig"),
           py::arg("options") = StreamOptions())
      .def("addFrame",
           [](StreamEstimator &s, const py::object &row, const py::object &observations) {
             const MotionSample sample = sampleOf(row);
             const std::vector<FeatureObservation> obs = featuresOf(observations);
             py::gil_scoped_release release;
             s.addFrame(sample, obs);
           },
           py::arg("row"), py::arg("observations"),
           "One frame: row, a motion row of 6 or 8 numbers (as MotionLog.samples; frames increasing); "
           "observations: dict {id: (u, v)} or (K, 3) float64 [id, u (px), v (px)].")
      .def("estimate", &StreamEstimator::estimate, py::arg("id"), "PointEstimate of `id` at its last observed frame.")
      .def("estimateAt", [](const StreamEstimator &s, long id, const py::object &row) {
             return s.estimateAt(id, sampleOf(row));
           }, py::arg("id"), py::arg("row"), "PointEstimate of `id` carried to the camera of motion row `row`.")
      .def("forget", &StreamEstimator::forget, py::arg("id"), "Drop feature `id`.")
      .def_property_readonly("method", [](const StreamEstimator &s) { return std::string(toString(s.method())); });
}

} // namespace yawdepth::python
