/*
  servo_ibvs_yawing_camera: image-based visual servoing of a mobile robot with a yawing (pan)
  camera on the four corners of a tag, with each feature's depth Z from
    --depth true       the true depth (what a depth sensor would give),
    --depth constant   desired depth x (1 + --constant-error) for every feature (ViSP's usual guess),
    --depth estimated  yawdepth::DepthProvider: the depth from the robot's odometry and the image
                       motion, the prior (1 m) until each feature's estimate has converged.

  The robot: a unicycle (v, omega) with the pan axis 0.2 m ahead of the wheel axle and the camera
  3 cm ahead of the pan axis; the servo drives (v, omega, pan rate) with vpServo
  (EYEINHAND_L_cVe_eJe, interaction matrix CURRENT: the current depths are what the estimate
  changes). --view front: the robot drives toward the tag (camera along the motion: depth poorly
  observed); --view side: the camera panned 90 degrees, the robot drives past the tag. Odometry
  (dead-reckoned, 2 % velocity noise), pan readings (0.03 deg) and corner pixels (0.3 px) are noisy.
  --yaw-helper adds yawdepth::recommendYawRate() as a secondary task (ViSP's large projection
  operator) while some depth has not converged.

  Writes a PNG only when asked (--png FILE; nothing by default): the corners' image trajectories and
  the depths over time. --display opens a ViSP window. The last line is
    converged iterations=N final_error=E      (E: true mean corner error in pixels)
  or  diverged iterations=N final_error=E reason=R
*/
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <visp3/core/vpConfig.h>
#include <visp3/core/vpImage.h>
#include <visp3/gui/vpDisplayOpenCV.h>
#include <visp3/gui/vpDisplayX.h>

#include <yawdepth/servo/servo_simulation.h>

namespace {

void usage()
{
  std::printf("usage: servo_ibvs_yawing_camera [--depth true|constant|estimated] [--constant-error E]\n"
              "       [--view front|side] [--yaw-helper] [--prior Z] [--seed N] [--sigma-px S] [--sigma-odom R]\n"
              "       [--sigma-pan RAD] [--max-iterations N] [--png FILE|none] [--display] [--quiet]\n");
}

const cv::Scalar kColours[] = {{40, 40, 220}, {40, 160, 40}, {220, 90, 30}, {160, 40, 160}};

void writePlot(const std::string &path, const yawdepth::ServoSimOptions &o, const yawdepth::ServoSimResult &r)
{
  const int W = 640, H = 480, pad = 40;
  cv::Mat img(H + 2 * pad, 2 * W + 3 * pad, CV_8UC3, cv::Scalar(255, 255, 255));
  // Left: image plane.
  const cv::Point off(pad, pad);
  cv::rectangle(img, off, off + cv::Point(W, H), cv::Scalar(0, 0, 0));
  cv::putText(img, "corner trajectories (px), x = desired", off + cv::Point(5, -10), cv::FONT_HERSHEY_SIMPLEX, 0.5,
              cv::Scalar(0, 0, 0));
  const double sx = double(W) / o.camera.width(), sy = double(H) / o.camera.height();
  for (std::size_t i = 0; i < r.desired_pixels.size(); ++i) {
    std::vector<cv::Point> pts;
    for (const auto &st : r.steps)
      if (i < st.pixels.size() && std::isfinite(st.pixels[i].x()))
        pts.emplace_back(off + cv::Point(int(st.pixels[i].x() * sx), int(st.pixels[i].y() * sy)));
    if (pts.size() > 1)
      cv::polylines(img, pts, false, kColours[i % 4], 1, cv::LINE_AA);
    if (!pts.empty())
      cv::circle(img, pts.front(), 4, kColours[i % 4], 1, cv::LINE_AA);
    const cv::Point d = off + cv::Point(int(r.desired_pixels[i].x() * sx), int(r.desired_pixels[i].y() * sy));
    cv::drawMarker(img, d, kColours[i % 4], cv::MARKER_TILTED_CROSS, 10, 2);
  }
  // Right: depth over time.
  const cv::Point off2(2 * pad + W, pad);
  cv::rectangle(img, off2, off2 + cv::Point(W, H), cv::Scalar(0, 0, 0));
  double zmax = 0;
  for (const auto &st : r.steps) {
    for (double z : st.true_Z)
      zmax = std::max(zmax, z);
    for (double z : st.used_Z)
      zmax = std::max(zmax, z);
  }
  zmax = std::max(zmax * 1.1, 0.1);
  const double tmax = std::max(1.0, r.steps.empty() ? 1.0 : r.steps.back().time);
  auto P = [&](double t, double z) {
    return off2 + cv::Point(int(t / tmax * (W - 1)), int((1.0 - std::min(z, zmax) / zmax) * (H - 1)));
  };
  char label[200];
  std::snprintf(label, sizeof label, "depth Z (m) over %.1f s, 0..%.2f m: thin = true, thick = used (%s)", tmax, zmax,
                yawdepth::toString(o.depth));
  cv::putText(img, label, off2 + cv::Point(5, -10), cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(0, 0, 0));
  for (std::size_t i = 0; i < r.desired_pixels.size(); ++i) {
    std::vector<cv::Point> t, u;
    for (const auto &st : r.steps) {
      if (i < st.true_Z.size())
        t.push_back(P(st.time, st.true_Z[i]));
      if (i < st.used_Z.size())
        u.push_back(P(st.time, st.used_Z[i]));
    }
    if (t.size() > 1)
      cv::polylines(img, t, false, kColours[i % 4], 1, cv::LINE_AA);
    if (u.size() > 1)
      cv::polylines(img, u, false, kColours[i % 4], 2, cv::LINE_AA);
  }
  if (!cv::imwrite(path, img))
    std::fprintf(stderr, "servo_ibvs_yawing_camera: cannot write %s\n", path.c_str());
}

} // namespace

int main(int argc, char **argv)
{
  yawdepth::ServoSimOptions o;
  std::string png = "none"; // write nothing unless asked: a run must not litter the current folder
  bool display = false, quiet = false, verbose = false;
  try {
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      auto next = [&]() -> std::string {
        if (i + 1 >= argc)
          throw std::runtime_error("missing value after " + a);
        return argv[++i];
      };
      if (a == "--depth")
        o.depth = yawdepth::servoDepthModeFromString(next());
      else if (a == "--constant-error")
        o.constant_error = std::stod(next());
      else if (a == "--view") {
        const std::string v = next();
        if (v != "front" && v != "side")
          throw std::runtime_error("--view: front or side");
        o.side_view = v == "side";
      } else if (a == "--yaw-helper")
        o.yaw_helper = true;
      else if (a == "--converged-sigma")
        o.provider.converged_relative_sigma = std::stod(next());
      else if (a == "--prior")
        o.provider.prior_depth = std::stod(next());
      else if (a == "--seed")
        o.seed = std::stoull(next());
      else if (a == "--sigma-px")
        o.sigma_px = std::stod(next());
      else if (a == "--sigma-odom")
        o.sigma_odom_rel = std::stod(next());
      else if (a == "--sigma-pan")
        o.sigma_pan = std::stod(next());
      else if (a == "--max-iterations")
        o.max_iterations = std::stoi(next());
      else if (a == "--png")
        png = next();
      else if (a == "--display")
        display = true;
      else if (a == "--verbose")
        verbose = true;
      else if (a == "--quiet")
        quiet = true;
      else if (a == "--help" || a == "-h") {
        usage();
        return 0;
      } else
        throw std::runtime_error("unknown option " + a);
    }
  } catch (const std::exception &e) {
    std::fprintf(stderr, "servo_ibvs_yawing_camera: %s\n", e.what());
    usage();
    return 2;
  }
  // The estimator's noise model: what the simulated robot's sensors have.
  o.provider.noise.sigma_px = std::max(o.sigma_px, 0.05);
  o.provider.noise.sigma_yaw = std::max(o.sigma_pan, 1e-4);

  // Optional ViSP display of the image plane.
  vpImage<unsigned char> I(o.camera.height(), o.camera.width(), 255);
  std::unique_ptr<vpDisplay> disp;
  if (display) {
#if defined(VISP_HAVE_X11)
    disp.reset(new vpDisplayX(I, 0, 0, "servo_ibvs_yawing_camera"));
#elif defined(VISP_HAVE_OPENCV)
    disp.reset(new vpDisplayOpenCV(I, 0, 0, "servo_ibvs_yawing_camera"));
#else
    std::fprintf(stderr, "servo_ibvs_yawing_camera: no ViSP display available, running headless\n");
#endif
  }

  std::printf("servo: depth=%s%s view=%s yaw-helper=%s seed=%llu\n", yawdepth::toString(o.depth),
              o.depth == yawdepth::ServoDepthMode::Constant
                  ? (" (Z = " + std::to_string(o.desired_depth * (1 + o.constant_error)) + " m)").c_str()
                  : "",
              o.side_view ? "side" : "front", o.yaw_helper ? "on" : "off", static_cast<unsigned long long>(o.seed));
  std::vector<yawdepth::ServoSimStep> trail;
  yawdepth::ServoSimResult r;
  try {
    r = yawdepth::runServoSimulation(o, [&](const yawdepth::ServoSimStep &st) {
      if (!quiet && st.iteration % 25 == 0) {
        std::printf("it %4d  error %8.3f px  Z used", st.iteration, st.error_px);
        for (std::size_t i = 0; i < st.used_Z.size(); ++i)
          std::printf(" %.3f%s", st.used_Z[i], st.converged.size() > i && st.converged[i] ? "*" : "");
        if (verbose)
          for (std::size_t i = 0; i < st.status.size(); ++i)
            std::printf(" [%s %.3f]", yawdepth::toString(st.status[i]), st.estimate_Z[i]);
        if (verbose && st.qdot.size() == 3)
          std::printf(" qdot %.3f %.3f %.3f helper %.3f", st.qdot[0], st.qdot[1], st.qdot[2], st.yaw_helper_rate);
        std::printf("  (true");
        for (double z : st.true_Z)
          std::printf(" %.3f", z);
        std::printf(")\n");
      }
      if (disp) {
        trail.push_back(st);
        vpDisplay::display(I);
        for (const auto &t : trail)
          for (const auto &p : t.pixels)
            vpDisplay::displayPoint(I, vpImagePoint(p.y(), p.x()), vpColor::blue);
        for (const auto &p : st.pixels)
          vpDisplay::displayCross(I, vpImagePoint(p.y(), p.x()), 12, vpColor::red, 2);
        vpDisplay::flush(I);
      }
    });
  } catch (const std::exception &e) {
    std::fprintf(stderr, "servo_ibvs_yawing_camera: %s\n", e.what());
    return 1;
  }
  if (png != "none")
    writePlot(png, o, r);
  if (disp && !quiet) {
    vpDisplay::displayText(I, 20, 20, "Click to quit", vpColor::red);
    vpDisplay::flush(I);
    vpDisplay::getClick(I);
  }
  if (r.converged)
    std::printf("converged iterations=%d final_error=%.4f\n", r.iterations, r.final_error_px);
  else
    std::printf("diverged iterations=%d final_error=%.4f reason=%s\n", r.iterations, r.final_error_px, r.reason.c_str());
  return r.converged ? 0 : 3;
}
