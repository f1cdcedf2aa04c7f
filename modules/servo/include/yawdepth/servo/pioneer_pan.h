#pragma once
/*!
  \file pioneer_pan.h
  \brief ViSP's Pioneer with a pan head (vpPioneerPan, vpSimulatorPioneerPan) in yawdepth's terms:
  its rig, and its odometry as a MotionSample.

  Frames. ViSP's robot world w has x forward (at theta = 0), y to the left and z up; the robot's
  odometry is (x_m, y_m, theta) of the point between the wheels, theta positive to the left; the pan
  joint q turns the camera to the right for q > 0 (about the pan frame's z, which points down).
  yawdepth's odometry world o and vision frame v (the paper's) have x to the right, y down and z
  forward; the vision frame's origin is on the pan axis (0.103 m ahead of the wheels' axis, 0.27 m
  above the floor), its heading is positive to the right and its yaw is q. So
  \f[ {}^oR_w = \begin{pmatrix} 0 & -1 & 0 \\ 0 & 0 & -1 \\ 1 & 0 & 0 \end{pmatrix},\quad
      (x, y, z)_v = {}^oR_w\,(x_m + p_x\cos\theta,\; y_m + p_x\sin\theta,\; p_z),\quad
      h = -\theta,\quad \psi = q \f]
  with \f$ p_x = 0.103 \f$ m and \f$ p_z = 0.27 \f$ m (vpPioneerPan's mMp). The camera sits on the
  pan axis, 0.065 m above the pan frame (vpPioneerPan's cMe), looking along the vision frame's z at
  q = 0: pioneerPanRig() is YawRig((0, -0.065, 0)). Then, for every pose and pan angle,
  \f[ \mathrm{wMc}(\mathrm{pioneerPanRig}(), \mathrm{pioneerPanOdometry}(x_m, y_m, \theta, q))
      = {}^oM_w \; {}^wM_c \f]
  with \f$ {}^wM_c \f$ what vpSimulatorPioneerPan::getPosition() gives and \f$ {}^oM_w \f$ =
  pioneerPanWorld() (a rotation, no translation). The camera's optical centre is on the pan axis:
  panning alone gives no parallax on this robot, driving does.
*/
#include <visp3/core/vpHomogeneousMatrix.h>
#include <yawdepth/geometry/rig.h>

namespace yawdepth {

/*! \brief The rig of ViSP's vpPioneerPan: the optical centre 0.065 m above the pan frame, on its axis. */
YawRig pioneerPanRig();

/*!
  \brief The Pioneer's odometry and pan reading as a planar MotionSample (see the file).
  \param x_m, y_m Position of the point between the wheels in ViSP's world frame (m).
  \param theta Heading in ViSP's world frame (rad, positive to the left).
  \param q_pan Pan joint reading (rad, positive to the right).
  \param frame The sample's frame number.
*/
MotionSample pioneerPanOdometry(double x_m, double y_m, double theta, double q_pan, long frame = 0);

/*! \brief \f$ {}^oM_w \f$: ViSP's robot world frame in the odometry world of pioneerPanOdometry(). */
vpHomogeneousMatrix pioneerPanWorld();

} // namespace yawdepth
