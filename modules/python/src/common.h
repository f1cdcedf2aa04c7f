#pragma once
// Conversions between numpy arrays and the C++ types, shared by the binding files. No estimation
// logic: shapes are checked and values copied; every error is a yawdepth::Error (yawdepth.Error).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <string>
#include <vector>
#include <visp3/core/vpHomogeneousMatrix.h>
#include <yawdepth/core/types.h>
#include <yawdepth/io/files.h>

namespace yawdepth::python {

namespace py = pybind11;
using Array = py::array_t<double, py::array::c_style | py::array::forcecast>;

/*! \brief A float64 array of `rows` x `cols` (C order). */
Array newArray(py::ssize_t rows, py::ssize_t cols);
/*! \brief `a` as an (N, cols) array; throws yawdepth::Error naming `what` otherwise. */
Array asRows(const py::handle &a, py::ssize_t cols, const std::string &what);
/*! \brief A 4x4 numpy pose as a ViSP homogeneous matrix (checked to be a rigid transform by ViSP). */
vpHomogeneousMatrix toPose(const py::handle &a, const std::string &what);
/*! \brief A ViSP homogeneous matrix as a 4x4 numpy array. */
Array fromPose(const vpHomogeneousMatrix &M);
/*! \brief An Eigen matrix (any size) as a numpy array. */
template <typename M> Array fromEigen(const M &m)
{
  Array a = newArray(m.rows(), m.cols());
  auto r = a.mutable_unchecked<2>();
  for (py::ssize_t i = 0; i < m.rows(); ++i)
    for (py::ssize_t j = 0; j < m.cols(); ++j)
      r(i, j) = m(i, j);
  return a;
}
/*! \brief Whether a float64 cell holds an integer (frame numbers, ids). */
inline bool isInteger(double v) { return std::isfinite(v) && v == std::floor(v) && std::fabs(v) <= 9007199254740992.0; }
/*! \brief An integer held in a float64 cell; throws naming `what` (row `row`) unless it is one. The
    message is built only on failure: this runs once per array row. */
long integerOf(double v, const char *what, py::ssize_t row, const char *column);

/*! \brief Motion samples as (N, 6) planar [frame, x, y, z, heading, yaw] or (N, 8) 6-DoF
    [frame, tx, ty, tz, tux, tuy, tuz, yaw]. */
Array motionArray(const std::vector<MotionSample> &samples);
/*! \brief The inverse of motionArray() (the width tells the form). */
std::vector<MotionSample> motionSamples(const py::handle &a);
/*! \brief One motion row (6 or 8 numbers, as a MotionLog.samples row) as a MotionSample. */
MotionSample sampleOf(const py::handle &row);
/*! \brief A MotionLog, or an array as motionSamples() reads it (a `yaw` column). */
MotionLog motionLogOf(const py::handle &motion);

/*! \brief Tracks as (M, 4) [frame, id, u, v], rows by id then frame (the order of readTracksCsv()). */
Array tracksArray(const std::vector<Track> &tracks);
/*! \brief The inverse: rows grouped by id (ascending), each track's rows by frame; a repeated
    (frame, id) pair or a non-integer frame or id is an error. */
std::vector<Track> tracksOf(const py::handle &a);

/*! \brief Points as the structured array of docs/python.md (the points CSV's columns). */
py::array pointsArray(const std::vector<PointRow> &rows);

void bindIo(py::module_ &m);
void bindEstimation(py::module_ &m);
void bindServo(py::module_ &m);
void bindFeatures(py::module_ &m);

} // namespace yawdepth::python
