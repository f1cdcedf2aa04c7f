#include <yawdepth/servo/servo_simulation.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <visp3/core/vpVelocityTwistMatrix.h>
#include <visp3/visual_features/vpFeaturePoint.h>
#include <visp3/vs/vpServo.h>
#include <yawdepth/error.h>

namespace yawdepth {

MotionSample UnicyclePanRobot::sample(long frame) const
{
  MotionSample s;
  s.frame = frame;
  const Eigen::Vector3d p = Eigen::Vector3d(x, 0, z) + rotY(heading) * Eigen::Vector3d(0, 0, axle_to_yaw);
  s.x = p.x();
  s.y = p.y();
  s.z = p.z();
  s.heading = heading;
  s.yaw = pan;
  return s;
}

vpHomogeneousMatrix UnicyclePanRobot::wMc() const { return yawdepth::wMc(rig, sample()); }

vpMatrix UnicyclePanRobot::cJq() const
{
  // Camera origin in the robot frame (wheel axle centre, camera convention), and e_y x p = (p_z, 0, -p_x).
  const Eigen::Matrix3d Rq = rotY(pan);
  const Eigen::Vector3d r_off = Rq * rig.cameraOffset();
  const Eigen::Vector3d r_c = Eigen::Vector3d(0, 0, axle_to_yaw) + r_off;
  auto cross_y = [](const Eigen::Vector3d &p) { return Eigen::Vector3d(p.z(), 0, -p.x()); };
  const Eigen::Vector3d lin_v = Rq.transpose() * Eigen::Vector3d(0, 0, 1);
  const Eigen::Vector3d lin_w = Rq.transpose() * cross_y(r_c);
  const Eigen::Vector3d lin_q = Rq.transpose() * cross_y(r_off);
  vpMatrix J(6, 3, 0.0);
  for (unsigned i = 0; i < 3; ++i) {
    J[i][0] = lin_v(i);
    J[i][1] = lin_w(i);
    J[i][2] = lin_q(i);
  }
  J[4][1] = 1.0;
  J[4][2] = 1.0;
  return J;
}

Eigen::Vector3d UnicyclePanRobot::visionVelocity(double v, double omega) const
{
  return Eigen::Vector3d(omega * axle_to_yaw, 0, v);
}

void UnicyclePanRobot::step(const vpColVector &qdot, double dt)
{
  if (qdot.size() != 3)
    throw Error("robot: expected 3 joint rates (v, omega, pan rate)");
  const double v = qdot[0], w = qdot[1];
  const double h0 = heading, h1 = heading + w * dt;
  if (std::abs(w * dt) > 1e-12) {
    x += v / w * (std::cos(h0) - std::cos(h1));
    z += v / w * (std::sin(h1) - std::sin(h0));
  } else {
    x += v * dt * std::sin(h0);
    z += v * dt * std::cos(h0);
  }
  heading = h1;
  pan += qdot[2] * dt;
}

void UnicyclePanRobot::placeCamera(const vpHomogeneousMatrix &wMc_target, double heading_rad)
{
  const double psi = std::atan2(wMc_target[0][2], wMc_target[0][0]);
  heading = heading_rad;
  pan = psi - heading_rad;
  const Eigen::Vector3d c(wMc_target[0][3], wMc_target[1][3], wMc_target[2][3]);
  const Eigen::Vector3d p = c - rotY(heading) * (Eigen::Vector3d(0, 0, axle_to_yaw) + rotY(pan) * rig.cameraOffset());
  x = p.x();
  z = p.z();
}

const char *toString(ServoDepthMode m)
{
  switch (m) {
  case ServoDepthMode::True:
    return "true";
  case ServoDepthMode::Constant:
    return "constant";
  case ServoDepthMode::Estimated:
    return "estimated";
  }
  return "?";
}

ServoDepthMode servoDepthModeFromString(const std::string &s)
{
  if (s == "true")
    return ServoDepthMode::True;
  if (s == "constant")
    return ServoDepthMode::Constant;
  if (s == "estimated")
    return ServoDepthMode::Estimated;
  throw Error("unknown depth mode '" + s + "' (expected true, constant or estimated)");
}

CameraModel ServoSimOptions::defaultCamera() { return CameraModel::brown(600, 600, 320, 240, {-0.05, 0, 0, 0}, 640, 480); }

namespace {

// Point the camera (heading and axle fixed) at `target` plus `offset` rad of yaw. The optical centre
// moves with the pan (it is off the pan axis), so the pan is found by a fixed-point iteration.
void aimPan(UnicyclePanRobot &robot, const Eigen::Vector3d &target, double offset)
{
  for (int it = 0; it < 20; ++it) {
    const vpHomogeneousMatrix M = robot.wMc();
    const Eigen::Vector3d d = target - Eigen::Vector3d(M[0][3], M[1][3], M[2][3]);
    robot.pan = std::atan2(d.x(), d.z()) + offset - robot.heading;
  }
}

} // namespace

ServoSimResult runServoSimulation(const ServoSimOptions &o, const std::function<void(const ServoSimStep &)> &on_step)
{
  if (!(o.dt > 0) || !(o.lambda > 0) || o.max_iterations < 1 || !(o.tolerance_px > 0) || !(o.tag_size > 0) ||
      !(o.desired_depth > 0) || !(o.sigma_px >= 0) || !(o.sigma_odom_rel >= 0) || !(o.sigma_pan >= 0) ||
      !(o.max_v > 0) || !(o.max_omega > 0) || !(o.max_pan_rate > 0))
    throw Error("servo simulation: invalid options");
  if (o.depth == ServoDepthMode::Constant && !(o.constant_error > -1.0))
    throw Error("servo simulation: constant_error must be above -1 (the depth must stay positive)");
  const CameraModel &camera = o.camera;
  if (camera.width() == 0 || camera.height() == 0)
    throw Error("servo simulation: the camera needs an image size");

  // The tag: corners ids 1..4 (bottom-left, bottom-right, top-right, top-left), centre at the world origin, facing -Z.
  const double h = o.tag_size / 2;
  const std::vector<long> ids{1, 2, 3, 4};
  const std::vector<Eigen::Vector3d> w_P{{-h, h, 0}, {h, h, 0}, {h, -h, 0}, {-h, -h, 0}};
  const std::size_t n = w_P.size();

  // Desired camera: desired_depth in front of the tag, facing it.
  vpHomogeneousMatrix wMcd;
  wMcd[2][3] = -o.desired_depth;
  UnicyclePanRobot robot;
  robot.axle_to_yaw = o.axle_to_yaw;
  robot.rig = o.rig;
  const double heading_d = o.side_view ? -M_PI / 2 : 0.0;
  robot.placeCamera(wMcd, heading_d);
  // Start: back along the robot's path, off to one side, turned, the pan aimed near the tag.
  {
    const Eigen::Vector3d fwd(std::sin(heading_d), 0, std::cos(heading_d)), right(std::cos(heading_d), 0, -std::sin(heading_d));
    const double back = o.side_view ? 0.5 : 0.8, lateral = o.side_view ? -0.12 : 0.15, turn = o.side_view ? 0.1 : 0.15;
    const Eigen::Vector3d p = Eigen::Vector3d(robot.x, 0, robot.z) - back * fwd + lateral * right;
    robot.x = p.x();
    robot.z = p.z();
    robot.heading = heading_d + turn;
    aimPan(robot, Eigen::Vector3d::Zero(), 0.05);
  }
  UnicyclePanRobot odometry = robot; // dead reckoning, from the true start

  // Desired features.
  ServoSimResult result;
  std::vector<vpFeaturePoint> s(n), sd(n);
  const vpHomogeneousMatrix cdMw = wMcd.inverse();
  for (std::size_t i = 0; i < n; ++i) {
    const vpColVector P = cdMw * vpColVector{w_P[i].x(), w_P[i].y(), w_P[i].z(), 1.0};
    sd[i].buildFrom(P[0] / P[2], P[1] / P[2], P[2]);
    result.desired_pixels.push_back(camera.project(Eigen::Vector2d(P[0] / P[2], P[1] / P[2])));
  }

  vpServo task;
  task.setServo(vpServo::EYEINHAND_L_cVe_eJe);
  task.setInteractionMatrixType(vpServo::CURRENT);
  task.setLambda(o.lambda);
  task.set_cVe(vpVelocityTwistMatrix());
  for (std::size_t i = 0; i < n; ++i)
    task.addFeature(s[i], sd[i]);

  std::mt19937_64 rng(o.seed);
  std::normal_distribution<double> N01(0.0, 1.0);
  DepthProvider provider(camera, o.rig, o.provider);

  vpColVector qdot(3, 0.0);
  result.reason = "max_iterations";
  for (int k = 0; k <= o.max_iterations; ++k) {
    ServoSimStep st;
    st.iteration = k;
    st.time = k * o.dt;
    st.robot = robot.sample(k);
    const vpHomogeneousMatrix cMw = robot.wMc().inverse();
    bool lost = false;
    std::vector<Eigen::Vector3d> c_P(n);
    std::vector<std::pair<long, vpImagePoint>> observed;
    for (std::size_t i = 0; i < n; ++i) {
      const vpColVector P = cMw * vpColVector{w_P[i].x(), w_P[i].y(), w_P[i].z(), 1.0};
      c_P[i] = Eigen::Vector3d(P[0], P[1], P[2]);
      if (!(P[2] > 1e-3)) {
        lost = true;
        st.pixels.emplace_back(Eigen::Vector2d::Constant(std::numeric_limits<double>::quiet_NaN()));
        continue;
      }
      const Eigen::Vector2d uv = camera.project(Eigen::Vector2d(P[0] / P[2], P[1] / P[2]));
      if (!(uv.x() >= 0 && uv.x() <= camera.width() - 1 && uv.y() >= 0 && uv.y() <= camera.height() - 1))
        lost = true;
      st.pixels.push_back(uv);
      observed.emplace_back(ids[i], vpImagePoint(uv.y() + o.sigma_px * N01(rng), uv.x() + o.sigma_px * N01(rng)));
      st.true_Z.push_back(P[2]);
    }
    double err = 0;
    for (std::size_t i = 0; i < n; ++i)
      err += (st.pixels[i] - result.desired_pixels[i]).norm();
    st.error_px = err / n;
    result.final_error_px = st.error_px;
    result.iterations = k;
    if (lost) {
      result.reason = "lost_features";
      break;
    }
    if (!std::isfinite(st.error_px)) {
      result.reason = "not_finite";
      break;
    }
    if (st.error_px < o.tolerance_px) {
      result.converged = true;
      result.reason = "converged";
      result.steps.push_back(st);
      if (on_step)
        on_step(result.steps.back());
      break;
    }
    if (k == o.max_iterations)
      break;

    // Odometry as the robot reports it: dead-reckoned pose, noisy pan reading.
    MotionSample odo = odometry.sample(k);
    odo.yaw = robot.pan + o.sigma_pan * N01(rng);

    // Depth of each feature.
    if (o.depth == ServoDepthMode::Estimated)
      provider.update(odo, observed);
    for (std::size_t i = 0; i < n; ++i) {
      double Z = 1.0, sigma = 0, est = std::numeric_limits<double>::quiet_NaN();
      bool conv = false;
      Status status = Status::TooFewFrames;
      switch (o.depth) {
      case ServoDepthMode::True:
        Z = c_P[i].z();
        break;
      case ServoDepthMode::Constant:
        Z = o.desired_depth * (1.0 + o.constant_error);
        break;
      case ServoDepthMode::Estimated: {
        const FeatureDepth f = provider.info(ids[i]);
        Z = f.depth;
        sigma = f.sigma;
        conv = f.converged;
        status = f.status;
        est = f.estimate;
        break;
      }
      }
      double x = 0, y = 0;
      camera.pixelToMeter(observed[i].second, x, y);
      s[i].buildFrom(x, y, Z);
      st.used_Z.push_back(Z);
      st.sigma_Z.push_back(sigma);
      st.converged.push_back(conv);
      st.status.push_back(status);
      st.estimate_Z.push_back(est);
    }

    // Control: the robot's Jacobian at the measured pan.
    UnicyclePanRobot measured = robot;
    measured.pan = odo.yaw;
    task.set_eJe(measured.cJq());
    qdot = task.computeControlLaw();

    if (o.yaw_helper && o.depth == ServoDepthMode::Estimated) {
      std::vector<YawHelperFeature> hf;
      bool any = false;
      for (std::size_t i = 0; i < n; ++i) {
        YawHelperFeature f;
        f.x = s[i].get_x();
        f.y = s[i].get_y();
        f.Z = s[i].get_Z();
        f.weight = st.converged[i] ? 0.0 : 1.0;
        any = any || !st.converged[i];
        hf.push_back(f);
      }
      if (any) {
        const YawRecommendation r =
            recommendYawRate(camera, o.rig, odo.yaw, measured.visionVelocity(qdot[0], qdot[1]), hf, o.helper);
        vpColVector de2dt(3, 0.0);
        de2dt[2] = r.rate;
        st.yaw_helper_rate = r.rate;
        qdot += task.secondaryTask(de2dt, true);
      }
    }
    // Saturation: scale every rate together.
    const double scale = std::max({1.0, std::abs(qdot[0]) / o.max_v, std::abs(qdot[1]) / o.max_omega,
                                   std::abs(qdot[2]) / o.max_pan_rate});
    qdot /= scale;
    if (!std::isfinite(qdot.sumSquare())) {
      result.reason = "not_finite";
      break;
    }
    st.qdot = qdot;
    result.steps.push_back(st);
    if (on_step)
      on_step(result.steps.back());

    robot.step(qdot, o.dt);
    vpColVector measured_rates = qdot;
    measured_rates[0] *= 1.0 + o.sigma_odom_rel * N01(rng);
    measured_rates[1] *= 1.0 + o.sigma_odom_rel * N01(rng);
    odometry.step(measured_rates, o.dt);
  }
  return result;
}

} // namespace yawdepth
