// `yawdepth._yawdepth`: the conversions, the exception, cameras, rigs and the files (motion, tracks,
// points, rig, camera). See docs/python.md; the names are the C++ names.
#include "common.h"

#include <cmath>
#include <algorithm>
#include <sstream>
#include <yawdepth/camera/camera_file.h>
#include <yawdepth/error.h>
#include <yawdepth/io/recording.h>

namespace yawdepth::python {

Array newArray(py::ssize_t rows, py::ssize_t cols) { return Array({rows, cols}); }

Array asRows(const py::handle &a, py::ssize_t cols, const std::string &what)
{
  Array arr = Array::ensure(a);
  if (!arr)
    throw Error(what + ": not an array of numbers");
  if (arr.ndim() == 1 && arr.shape(0) == 0)
    arr = Array(std::vector<py::ssize_t>{0, cols});
  if (arr.ndim() != 2 || arr.shape(1) != cols)
    throw Error(what + ": expected an (N, " + std::to_string(cols) + ") array, got shape " +
                py::str(py::tuple(a.attr("shape"))).cast<std::string>());
  return arr;
}

vpHomogeneousMatrix toPose(const py::handle &a, const std::string &what)
{
  Array arr = Array::ensure(a);
  if (!arr || arr.ndim() != 2 || arr.shape(0) != 4 || arr.shape(1) != 4)
    throw Error(what + ": expected a 4x4 array");
  auto r = arr.unchecked<2>();
  vpHomogeneousMatrix M;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) {
      if (!std::isfinite(r(i, j)))
        throw Error(what + ": not finite");
      M[i][j] = r(i, j);
    }
  if (!M.isAnHomogeneousMatrix(1e-6))
    throw Error(what + ": not a rigid transform (rotation not orthonormal or last row not 0 0 0 1)");
  return M;
}

Array fromPose(const vpHomogeneousMatrix &M)
{
  Array a = newArray(4, 4);
  auto r = a.mutable_unchecked<2>();
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      r(i, j) = M[i][j];
  return a;
}

long integerOf(double v, const char *what, py::ssize_t row, const char *column)
{
  if (!isInteger(v))
    throw Error(std::string(what) + ": row " + std::to_string(row) + ", " + column + ": not an integer: " +
                py::str(py::float_(v)).cast<std::string>());
  return static_cast<long>(v);
}

Array motionArray(const std::vector<MotionSample> &samples)
{
  const bool six = !samples.empty() && samples.front().six_dof;
  Array a = newArray(static_cast<py::ssize_t>(samples.size()), six ? 8 : 6);
  auto r = a.mutable_unchecked<2>();
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const MotionSample &s = samples[i];
    const py::ssize_t k = static_cast<py::ssize_t>(i);
    r(k, 0) = static_cast<double>(s.frame);
    r(k, 1) = s.x;
    r(k, 2) = s.y;
    r(k, 3) = s.z;
    if (six) {
      r(k, 4) = s.theta_u.x();
      r(k, 5) = s.theta_u.y();
      r(k, 6) = s.theta_u.z();
      r(k, 7) = s.yaw;
    } else {
      r(k, 4) = s.heading;
      r(k, 5) = s.yaw;
    }
  }
  return a;
}

std::vector<MotionSample> motionSamples(const py::handle &a)
{
  Array arr = Array::ensure(a);
  if (!arr || arr.ndim() != 2 || (arr.shape(1) != 6 && arr.shape(1) != 8))
    throw Error("motion: expected an (N, 6) array [frame, x, y, z, heading, yaw] or an (N, 8) array "
                "[frame, tx, ty, tz, tux, tuy, tuz, yaw]");
  const bool six = arr.shape(1) == 8;
  auto r = arr.unchecked<2>();
  std::vector<MotionSample> out(static_cast<std::size_t>(arr.shape(0)));
  for (py::ssize_t k = 0; k < arr.shape(0); ++k) {
    MotionSample &s = out[static_cast<std::size_t>(k)];
    s.frame = integerOf(r(k, 0), "motion", k, "frame");
    s.x = r(k, 1);
    s.y = r(k, 2);
    s.z = r(k, 3);
    s.six_dof = six;
    if (six) {
      s.theta_u = Eigen::Vector3d(r(k, 4), r(k, 5), r(k, 6));
      s.yaw = r(k, 7);
    } else {
      s.heading = r(k, 4);
      s.yaw = r(k, 5);
    }
  }
  return out;
}

MotionSample sampleOf(const py::handle &row)
{
  Array a = Array::ensure(row);
  if (!a || (a.size() != 6 && a.size() != 8))
    throw Error("motion row: expected 6 [frame, x, y, z, heading, yaw] or 8 [frame, tx, ty, tz, tux, tuy, tuz, yaw] "
                "numbers");
  return motionSamples(a.reshape({py::ssize_t(1), a.size()})).front();
}

MotionLog motionLogOf(const py::handle &motion)
{
  if (py::isinstance<MotionLog>(motion))
    return motion.cast<MotionLog>();
  MotionLog log;
  log.samples = motionSamples(motion);
  log.yaw_column = true;
  return log;
}

Array tracksArray(const std::vector<Track> &tracks)
{
  std::size_t n = 0;
  for (const Track &t : tracks)
    n += t.observations.size();
  Array a = newArray(static_cast<py::ssize_t>(n), 4);
  auto r = a.mutable_unchecked<2>();
  py::ssize_t k = 0;
  for (const Track &t : tracks)
    for (const Observation &o : t.observations) {
      r(k, 0) = static_cast<double>(o.frame);
      r(k, 1) = static_cast<double>(t.id);
      r(k, 2) = o.u;
      r(k, 3) = o.v;
      ++k;
    }
  return a;
}

std::vector<Track> tracksOf(const py::handle &a)
{
  Array arr = asRows(a, 4, "tracks [frame, id, u, v]");
  auto r = arr.unchecked<2>();
  struct Row {
    long id;
    Observation o;
  };
  std::vector<Row> rows(static_cast<std::size_t>(arr.shape(0)));
  for (py::ssize_t k = 0; k < arr.shape(0); ++k)
    rows[static_cast<std::size_t>(k)] = {integerOf(r(k, 1), "tracks", k, "id"),
                                         {integerOf(r(k, 0), "tracks", k, "frame"), r(k, 2), r(k, 3)}};
  std::stable_sort(rows.begin(), rows.end(), [](const Row &x, const Row &y) {
    return x.id != y.id ? x.id < y.id : x.o.frame < y.o.frame;
  });
  std::vector<Track> tracks;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    if (i > 0 && rows[i].id == rows[i - 1].id && rows[i].o.frame == rows[i - 1].o.frame)
      throw Error("tracks: frame " + std::to_string(rows[i].o.frame) + " and id " + std::to_string(rows[i].id) +
                  " repeated");
    if (tracks.empty() || tracks.back().id != rows[i].id)
      tracks.push_back(Track{rows[i].id, {}});
    tracks.back().observations.push_back(rows[i].o);
  }
  return tracks;
}

py::array pointsArray(const std::vector<PointRow> &rows)
{
  // Made once and kept for the life of the process (released, never decref'd: a static py::object
  // would be destroyed after the interpreter is gone).
  static const py::handle dtype = [] {
    py::module_ np = py::module_::import("numpy");
    py::list fields;
    fields.append(py::make_tuple("id", "<i8"));
    fields.append(py::make_tuple("frame", "<i8"));
    for (const char *f : {"x", "y", "z", "xc", "yc", "zc", "sigma_zc"})
      fields.append(py::make_tuple(f, "<f8"));
    fields.append(py::make_tuple("status", "<U16"));
    return np.attr("dtype")(fields).release();
  }();
  // The record layout: two int64, seven float64, 16 UCS-4 characters (numpy's 'U16').
  struct Record {
    std::int64_t id, frame;
    double v[7];
    char32_t status[16];
  };
  static_assert(sizeof(Record) == 16 + 56 + 64, "packed record");
  py::array out(py::reinterpret_borrow<py::dtype>(dtype), std::vector<py::ssize_t>{static_cast<py::ssize_t>(rows.size())});
  auto *rec = static_cast<Record *>(out.mutable_data());
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const PointEstimate &e = rows[i].estimate;
    Record &r = rec[i];
    r.id = rows[i].id;
    r.frame = e.frame;
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const double values[7] = {e.v_P.x(), e.v_P.y(), e.v_P.z(), e.c_P.x(), e.c_P.y(), e.c_P.z(), e.sigmaZ()};
    for (int j = 0; j < 7; ++j)
      r.v[j] = e.ok() ? values[j] : nan; // as the CSV: numbers only for ok points
    const char *s = toString(e.status);
    int j = 0;
    for (; j < 16 && s[j] != '\0'; ++j)
      r.status[j] = static_cast<char32_t>(s[j]);
    for (; j < 16; ++j)
      r.status[j] = 0;
  }
  return out;
}

/*! The rows of a points array back (for writePointsCsv of an array): sigma_zc as c_cov(2, 2). */
static std::vector<PointRow> pointRowsOf(const py::array &points)
{
  using Ints = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>;
  if (points.dtype().attr("names").is_none())
    throw Error("points: expected the structured points array of estimatePoints() or readPointsCsv()");
  const Ints ids = Ints::ensure(points[py::str("id")]);
  const Ints frames = Ints::ensure(points[py::str("frame")]);
  const char *names[7] = {"x", "y", "z", "xc", "yc", "zc", "sigma_zc"};
  std::vector<Array> cols;
  for (const char *n : names)
    cols.push_back(Array::ensure(points[py::str(n)]));
  const py::list status = points[py::str("status")].attr("tolist")();
  std::vector<PointRow> rows(static_cast<std::size_t>(ids.size()));
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const py::ssize_t k = static_cast<py::ssize_t>(i);
    PointEstimate &e = rows[i].estimate;
    rows[i].id = ids.at(k);
    e.frame = frames.at(k);
    e.status = statusFromString(status[i].cast<std::string>());
    e.v_P = Eigen::Vector3d(cols[0].at(k), cols[1].at(k), cols[2].at(k));
    e.c_P = Eigen::Vector3d(cols[3].at(k), cols[4].at(k), cols[5].at(k));
    e.c_cov(2, 2) = cols[6].at(k) * cols[6].at(k);
  }
  return rows;
}

static std::string distortionName(CameraModel::Distortion d)
{
  switch (d) {
  case CameraModel::Distortion::None: return "none";
  case CameraModel::Distortion::Brown: return "brown";
  case CameraModel::Distortion::ViSP: return "visp";
  case CameraModel::Distortion::KannalaBrandt: return "kannala_brandt";
  }
  return "none";
}

static Eigen::Vector3d vec3(const py::handle &a, const std::string &what)
{
  Array arr = Array::ensure(a);
  if (!arr || arr.size() != 3)
    throw Error(what + ": expected 3 numbers");
  return Eigen::Vector3d(arr.data()[0], arr.data()[1], arr.data()[2]);
}

void bindIo(py::module_ &m)
{
  // ---------------------------------------------------------------- camera
  py::class_<CameraModel> cam(m, "CameraModel", R"doc(
A camera: pinhole intrinsics (px), image size (px) and a distortion model (none, brown = OpenCV's
k1 k2 p1 p2 [k3 [k4 k5 k6]], visp = ViSP's kud, kannala_brandt = cv::fisheye's k1..k4).
Made by loadCameraFile() from any camera file the command line reads, or by CameraModel.brown() /
CameraModel.kannalaBrandt() from numbers; saved by saveCameraYaml() / saveRosCameraInfoYaml().)doc");
  cam.def_static("brown", &CameraModel::brown, py::arg("fx"), py::arg("fy"), py::arg("u0"), py::arg("v0"),
                 py::arg("coeffs") = std::vector<double>(), py::arg("width") = 0u, py::arg("height") = 0u,
                 R"doc(OpenCV/Brown camera: fx, fy focal lengths (px), u0, v0 principal point (px), coeffs 0, 4,
5 or 8 distortion coefficients in OpenCV order (k1 k2 p1 p2 k3 k4 k5 k6), width, height image size (px, 0 unknown).
Raises yawdepth.Error for another number of coefficients.)doc")
      .def_static("kannalaBrandt", &CameraModel::kannalaBrandt, py::arg("fx"), py::arg("fy"), py::arg("u0"),
                  py::arg("v0"), py::arg("k"), py::arg("width") = 0u, py::arg("height") = 0u,
                  "Kannala-Brandt fisheye camera (cv::fisheye, ROS/Kalibr `equidistant`): k = 4 coefficients k1..k4.")
      .def_property_readonly("kx", &CameraModel::kx, "Focal length along u (px).")
      .def_property_readonly("ky", &CameraModel::ky, "Focal length along v (px).")
      .def_property_readonly("u0", &CameraModel::u0, "Principal point u (px).")
      .def_property_readonly("v0", &CameraModel::v0, "Principal point v (px).")
      .def_property_readonly("width", &CameraModel::width, "Image width (px), 0 when unknown.")
      .def_property_readonly("height", &CameraModel::height, "Image height (px), 0 when unknown.")
      .def_property_readonly("K", [](const CameraModel &c) {
        Eigen::Matrix3d K;
        K << c.kx(), 0, c.u0(), 0, c.ky(), c.v0(), 0, 0, 1;
        return fromEigen(K);
      }, "(3, 3) float64: the intrinsic matrix [[kx, 0, u0], [0, ky, v0], [0, 0, 1]] (px).")
      .def_property_readonly("distortion", [](const CameraModel &c) { return distortionName(c.distortion()); },
                             "The distortion model: 'none', 'brown', 'visp' or 'kannala_brandt'.")
      .def_property_readonly("coefficients", [](const CameraModel &c) -> std::vector<double> {
        switch (c.distortion()) {
        case CameraModel::Distortion::Brown: return c.brownCoefficients();
        case CameraModel::Distortion::KannalaBrandt: return c.kannalaBrandtCoefficients();
        case CameraModel::Distortion::ViSP: return {c.parameters().get_kud()};
        default: return {};
        }
      }, "The distortion coefficients: brown k1 k2 p1 p2 k3 k4 k5 k6 (8), kannala_brandt k1..k4, visp [kud], none [].")
      .def("__repr__", [](const CameraModel &c) {
        std::ostringstream s;
        s << "CameraModel(kx=" << c.kx() << ", ky=" << c.ky() << ", u0=" << c.u0() << ", v0=" << c.v0()
          << ", " << c.width() << "x" << c.height() << ", " << distortionName(c.distortion()) << ")";
        return s.str();
      });
  m.def("loadCameraFile", &loadCameraFile, py::arg("path"), py::arg("camera_name") = "",
        R"doc(Load a camera file, as `yawdepth estimate --camera` does: ViSP XML (camera_name picks the camera;
empty when the file holds one), OpenCV YAML/XML, ROS camera_info YAML, Kalibr camchain (camera_name cam0, cam1, ...).
Raises yawdepth.Error with the command line's message.)doc");
  m.def("checkCameraPlausible", &checkCameraPlausible, py::arg("camera"), py::arg("what"),
        "Raise yawdepth.Error ('WHAT: implausible camera: why') for a camera that cannot be a real one.");
  m.def("saveCameraYaml", &saveCameraYaml, py::arg("path"), py::arg("camera"),
        "Write an OpenCV YAML camera file (what loadCameraFile() reads), atomically.");
  m.def("saveRosCameraInfoYaml", &saveRosCameraInfoYaml, py::arg("path"), py::arg("camera"),
        py::arg("camera_name") = "", "Write a ROS camera_info YAML file, atomically.");

  // ---------------------------------------------------------------- rig
  py::class_<YawRig>(m, "YawRig", R"doc(
The camera mount: the yaw joint (about the vision frame's +Y) and the camera's fixed pose on it.
YawRig(camera_offset=[x, y, z]) (m): the optical centre in the vision frame at yaw 0, axes parallel;
YawRig(camera_pose=vMc0) with a (4, 4) float64 pose of the camera in the vision frame at yaw 0 (m).
A rig file gives it by readRigFile(path).rig().)doc")
      .def(py::init([](const py::object &camera_offset, const py::object &camera_pose) {
             if (!camera_pose.is_none() && !camera_offset.is_none())
               throw Error("YawRig: give camera_offset or camera_pose, not both");
             if (!camera_pose.is_none())
               return YawRig(toPose(camera_pose, "camera_pose"));
             if (!camera_offset.is_none())
               return YawRig(vec3(camera_offset, "camera_offset"));
             return YawRig();
           }),
           py::arg("camera_offset") = py::none(), py::arg("camera_pose") = py::none())
      .def_property_readonly("cameraOffset", [](const YawRig &r) { return fromEigen(r.cameraOffset()); },
                             "(3, 1) float64: the optical centre in the vision frame at yaw 0 (m).")
      .def_property_readonly("cameraRotation", [](const YawRig &r) { return fromEigen(r.cameraRotation()); },
                             "(3, 3) float64: the camera's orientation in the vision frame at yaw 0.")
      .def_property_readonly("axisAligned", &YawRig::axisAligned,
                             "Whether the camera's axes are the vision frame's at yaw 0.")
      .def("vMc", [](const YawRig &r, double yaw) { return fromPose(r.vMc(yaw)); }, py::arg("yaw"),
           "(4, 4) float64: the camera's pose in the vision frame at `yaw` (rad), eq. (1) (m).")
      .def("cMv", [](const YawRig &r, double yaw) { return fromPose(r.cMv(yaw)); }, py::arg("yaw"),
           "(4, 4) float64: the vision frame's pose in the camera frame at `yaw` (rad) (m).");

  py::class_<RigFile>(m, "RigFile", R"doc(
A rig file's contents (YAML, docs/formats.md). camera_offset (3,) m, or camera_pose (6,)
[tx, ty, tz, tux, tuy, tuz] (m, rad; None when not given); yaw (rad) used when the motion has no yaw
column (None: not given); yaw_offset (rad), added to every yaw reading by applyRigFile();
time_offset (s, None: not given). rig() gives the YawRig.)doc")
      .def(py::init<>())
      .def_property("camera_offset", [](const RigFile &r) { return fromEigen(r.camera_offset); },
                    [](RigFile &r, const py::object &v) { r.camera_offset = vec3(v, "camera_offset"); },
                    "(3, 1) float64 [x, y, z] (m).")
      .def_property("camera_pose",
                    [](const RigFile &r) -> py::object {
                      if (!r.camera_pose)
                        return py::none();
                      Array a = newArray(6, 1);
                      for (int i = 0; i < 6; ++i)
                        a.mutable_at(i, 0) = (*r.camera_pose)[static_cast<unsigned>(i)];
                      return std::move(a);
                    },
                    [](RigFile &r, const py::object &v) {
                      if (v.is_none()) {
                        r.camera_pose.reset();
                        return;
                      }
                      Array a = Array::ensure(v);
                      if (!a || a.size() != 6)
                        throw Error("camera_pose: expected 6 numbers [tx, ty, tz, tux, tuy, tuz]");
                      r.camera_pose = vpPoseVector(a.data()[0], a.data()[1], a.data()[2], a.data()[3],
                                                   a.data()[4], a.data()[5]);
                    },
                    "(6, 1) float64 [tx, ty, tz, tux, tuy, tuz] (m, rad: theta-u) or None.")
      .def_readwrite("yaw", &RigFile::yaw, "Fixed yaw (rad) or None.")
      .def_readwrite("yaw_offset", &RigFile::yaw_offset, "Zero of the yaw reading (rad).")
      .def_readwrite("time_offset", &RigFile::time_offset, "Image time + time_offset = motion time (s), or None.")
      .def("rig", [](const RigFile &r) { return rigOf(r); }, "The YawRig this file describes (rigOf()).");
  m.def("readRigFile", &readRigFile, py::arg("path"), "Read a rig YAML file; raises yawdepth.Error.");
  m.def("writeRigFile", &writeRigFile, py::arg("path"), py::arg("rig_file"), "Write a rig YAML file, atomically.");
  m.def("rigWarnings", &rigWarnings, py::arg("rig_file"), py::arg("rig_path"),
        "Mistakes of units a rig file's numbers suggest, one line each (the command line's warnings).");

  // ---------------------------------------------------------------- motion
  py::class_<MotionLog>(m, "MotionLog", R"doc(
A motion log: `samples` (N, 6) float64 [frame, x (m), y (m), z (m), heading (rad), yaw (rad)] for a
planar log, or (N, 8) float64 [frame, tx, ty, tz (m), tux, tuy, tuz (rad, theta-u of wMv), yaw (rad)]
for a 6-DoF log; frames strictly increasing. `images` (one path per row, or empty), `yaw_column`
(whether the yaws were read from a column), `times` (s, or empty). MotionLog(samples) builds one
from an array (yaw_column True).)doc")
      .def(py::init([](const py::object &samples) { return motionLogOf(samples); }), py::arg("samples"))
      .def_property("samples", [](const MotionLog &l) { return motionArray(l.samples); },
                    [](MotionLog &l, const py::object &a) { l.samples = motionSamples(a); },
                    "(N, 6) or (N, 8) float64: see the class.")
      .def_property_readonly("six_dof", [](const MotionLog &l) { return !l.samples.empty() && l.samples.front().six_dof; },
                             "Whether the rows are 6-DoF poses.")
      .def_readwrite("images", &MotionLog::images, "Image path per row, or [].")
      .def_readwrite("yaw_column", &MotionLog::yaw_column, "Whether the yaws were read from a `yaw` column.")
      .def_readwrite("times", &MotionLog::times, "Each row's time (s, motion clock), or [].")
      .def("__len__", [](const MotionLog &l) { return l.samples.size(); });
  m.def("readMotionCsv", [](const std::string &path, std::optional<double> fixed_yaw) {
          return readMotionCsv(path, fixed_yaw);
        }, py::arg("path"), py::arg("fixed_yaw") = py::none(),
        "Read a motion log CSV (docs/formats.md); fixed_yaw (rad) for a file without a yaw column.");
  m.def("loadMotion", [](const std::string &path, const std::optional<RigFile> &rig_file, const std::string &format,
                         const std::string &images, std::optional<double> time_offset, std::optional<double> max_pose_gap) {
          MotionInput in;
          in.motion = {path};
          in.format = motionFormatFromString(format);
          in.images = images;
          if (time_offset)
            in.time_offset = *time_offset;
          if (max_pose_gap)
            in.max_pose_gap = *max_pose_gap;
          return loadMotion(in, rig_file ? rig_file->yaw : std::nullopt,
                            rig_file ? rig_file->time_offset : std::nullopt).log;
        }, py::arg("path"), py::arg("rig_file") = py::none(), py::arg("format") = "auto", py::arg("images") = "",
        py::arg("time_offset") = py::none(), py::arg("max_pose_gap") = py::none(),
        R"doc(Read any motion log the command line's --motion reads (yawdepth CSV, TUM, EuRoC, ...; `format`
as --motion-format), aligned to `images` when given, as `yawdepth estimate --motion` does: the rig
file gives the fixed yaw and the default time offset (s). max_pose_gap (s) None: the library's default.)doc");
  m.def("checkMotionSteps", &checkMotionSteps, py::arg("motion"), py::arg("motion_path"),
        "Raise yawdepth.Error for a step no motion between two frames can be (as the command line does).");
  m.def("motionWarnings", &motionWarnings, py::arg("motion"), py::arg("motion_path"),
        "Mistakes of units the motion's numbers suggest, one line each.");
  m.def("applyRigFile", [](const RigFile &r, MotionLog &log) { applyRigFile(r, log.samples); }, py::arg("rig_file"),
        py::arg("motion"), "Add the rig file's yaw_offset to every yaw of `motion` (in place).");
  m.def("writeMotionCsv", [](const std::string &path, const py::object &motion) {
          writeMotionCsv(path, motionLogOf(motion));
        }, py::arg("path"), py::arg("motion"), "Write a motion log CSV (a MotionLog or a samples array), atomically.");

  // ---------------------------------------------------------------- tracks and points
  m.def("readTracksCsv", [](const std::string &path) { return tracksArray(readTracksCsv(path)); }, py::arg("path"),
        "Read a tracks CSV: (M, 4) float64 [frame, id, u (px), v (px)], rows by id then frame.");
  m.def("writeTracksCsv", [](const std::string &path, const py::object &tracks) {
          writeTracksCsv(path, tracksOf(tracks));
        }, py::arg("path"), py::arg("tracks"), "Write (M, 4) [frame, id, u, v] tracks as a CSV, atomically.");
  m.def("checkTracksAgainstMotion", [](const py::object &tracks, const py::object &motion, const std::string &path) {
          checkTracksAgainstMotion(tracksOf(tracks), motionLogOf(motion), path);
        }, py::arg("tracks"), py::arg("motion"), py::arg("tracks_path"),
        "Raise yawdepth.Error naming the first observation whose frame is not in the motion.");
  m.def("readPointsCsv", [](const std::string &path) { return pointsArray(readPointsCsv(path)); }, py::arg("path"),
        "Read a points CSV as the structured points array (see estimatePoints).");
  m.def("writePointsCsv", [](const std::string &path, const py::array &points) {
          writePointsCsv(path, pointRowsOf(points));
        }, py::arg("path"), py::arg("points"),
        "Write a structured points array as the points CSV (17 significant digits), atomically.");
}

} // namespace yawdepth::python

PYBIND11_MODULE(_yawdepth, m)
{
  using namespace yawdepth::python;
  m.doc() = "yawdepth's C++ bindings; import `yawdepth`, not this module.";
  auto error = py::register_exception<yawdepth::Error>(m, "Error", PyExc_ValueError);
  error.attr("__doc__") = "yawdepth::Error: bad input (unreadable or malformed files, invalid parameters); "
                          "str(e) is the C++ one-line message. A subclass of ValueError.";
  bindIo(m);
  bindEstimation(m);
  bindServo(m);
  bindFeatures(m);
}
