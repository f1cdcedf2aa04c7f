#pragma once
/*
  What the servo examples share around their servo loops: the command line, the tutorial's
  four-point target (tutorial-ibvs-4pts: a 0.2 m square, its desired and current vpFeaturePoint's),
  the corners observed with pixel noise, and the printed lines. The loops themselves stay in each
  example.

  Header-only, ViSP and yawdepth::servo only: servo_ibvs_4pts.cpp and servo_pioneer_pan.cpp are
  also built alone against an installed yawdepth (tests/consumer, tests/consumer_servo), with this
  header found beside them; a copy of an example needs this file too.
*/
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <visp3/core/vpCameraParameters.h>
#include <visp3/core/vpHomogeneousMatrix.h>
#include <visp3/core/vpImagePoint.h>
#include <visp3/core/vpMeterPixelConversion.h>
#include <visp3/core/vpPoint.h>
#include <visp3/core/vpTranslationVector.h>
#include <visp3/visual_features/vpFeatureBuilder.h>
#include <visp3/visual_features/vpFeaturePoint.h>
#include <visp3/vs/vpServo.h>

#include <yawdepth/servo/depth_provider.h>

namespace servo_sim {

// ---- The command line ----

/*! The value after the current option (throws std::runtime_error when there is none). */
using NextValue = std::function<std::string()>;
/*! An example's own options: reads option `o` (its value from next()), false when it is not one. */
using OptionReader = std::function<bool(const std::string &o, const NextValue &next)>;

/*! Prints "NAME: MESSAGE" to stderr and the usage, and exits with 2: a command line the example cannot take. */
[[noreturn]] inline void exitWithUsage(const char *name, const std::string &message, void (*usage)())
{
  std::fprintf(stderr, "%s: %s\n", name, message.c_str());
  usage();
  std::exit(2);
}

/*!
  Reads the command line through `read`; --help or -h prints the usage and exits with 0. An unknown
  option, a missing value or a value `read` refuses (it throws) exits through exitWithUsage().
*/
inline void readOptions(int argc, char **argv, const char *name, void (*usage)(), const OptionReader &read)
{
  try {
    for (int i = 1; i < argc; ++i) {
      const std::string o = argv[i];
      const NextValue next = [&]() -> std::string {
        if (i + 1 >= argc)
          throw std::runtime_error("missing value after " + o);
        return argv[++i];
      };
      if (o == "--help" || o == "-h") {
        usage();
        std::exit(0);
      }
      if (!read(o, next))
        throw std::runtime_error("unknown option " + o);
    }
  } catch (const std::exception &e) {
    exitWithUsage(name, e.what(), usage);
  }
}

/*! The options servo_ibvs_4pts and servo_pioneer_pan share (each example sets its max_iterations). */
struct PointServoArgs {
  std::string depth_mode = "estimated"; //!< true, constant or estimated
  double constant_error = 0.0;          //!< constant depth: desired depth x (1 + constant_error)
  double sigma_px = 0.3;                //!< pixel noise of the observed corners (px)
  unsigned seed = 1;                    //!< noise seed
  int max_iterations = 0;               //!< stop after this many periods
  bool quiet = false, verbose = false;  //!< the progress lines: none, or every 10 iterations with the estimates
};

/*! Reads option `o` into `a` when it is one of PointServoArgs' (--depth, --constant-error, --seed, --sigma-px, --max-iterations, --quiet, --verbose). */
inline bool readPointServoOption(const std::string &o, const NextValue &next, PointServoArgs &a)
{
  if (o == "--depth") {
    a.depth_mode = next();
    if (a.depth_mode != "true" && a.depth_mode != "constant" && a.depth_mode != "estimated")
      throw std::runtime_error("--depth: true, constant or estimated");
  } else if (o == "--constant-error")
    a.constant_error = std::stod(next());
  else if (o == "--seed")
    a.seed = static_cast<unsigned>(std::stoul(next()));
  else if (o == "--sigma-px")
    a.sigma_px = std::stod(next());
  else if (o == "--max-iterations")
    a.max_iterations = std::stoi(next());
  else if (o == "--quiet")
    a.quiet = true;
  else if (o == "--verbose")
    a.verbose = true;
  else
    return false;
  return true;
}

// ---- The four-point target ----

/*! The tutorial's target: the corners of a 0.2 m square centred on the object frame's origin. */
inline void setSquare(vpPoint (&point)[4])
{
  point[0].setWorldCoordinates(-0.1, -0.1, 0);
  point[1].setWorldCoordinates(0.1, -0.1, 0);
  point[2].setWorldCoordinates(0.1, 0.1, 0);
  point[3].setWorldCoordinates(-0.1, 0.1, 0);
}

/*!
  The tutorial's features: pd[i] from the goal pose cdMo, p[i] from the start pose cMo, each pair
  added to the task; desired[i] the goal's pixels.
*/
inline void addSquareFeatures(vpServo &task, vpPoint (&point)[4], const vpCameraParameters &cam,
                              const vpHomogeneousMatrix &cdMo, const vpHomogeneousMatrix &cMo, vpFeaturePoint (&p)[4],
                              vpFeaturePoint (&pd)[4], vpImagePoint (&desired)[4])
{
  for (unsigned i = 0; i < 4; i++) {
    point[i].track(cdMo);
    vpFeatureBuilder::create(pd[i], point[i]);
    vpMeterPixelConversion::convertPoint(cam, point[i].get_x(), point[i].get_y(), desired[i]);
    point[i].track(cMo);
    vpFeatureBuilder::create(p[i], point[i]);
    task.addFeature(p[i], pd[i]);
  }
}

/*! What the camera sees of the square in one period. */
struct SquareView {
  std::vector<std::pair<long, vpImagePoint>> observed; //!< (corner, noisy pixel), as a tracker gives them
  double error = 0.0;                                  //!< true mean corner distance to the desired pixels (px)
  bool outside = false;                                //!< a corner is behind the camera or out of the image
};

/*!
  The square from the camera pose cMo: each corner's true projection (point[i] tracked, so that
  point[i].get_Z() is its true depth), then pixel noise, noise() for i then for j.
*/
template <class Noise>
SquareView observeSquare(vpPoint (&point)[4], const vpHomogeneousMatrix &cMo, const vpCameraParameters &cam,
                         unsigned width, unsigned height, const vpImagePoint (&desired)[4], Noise &&noise)
{
  SquareView view;
  for (unsigned i = 0; i < 4; i++) {
    point[i].track(cMo);
    vpImagePoint truth;
    vpMeterPixelConversion::convertPoint(cam, point[i].get_x(), point[i].get_y(), truth);
    view.error += vpImagePoint::distance(truth, desired[i]) / 4.0;
    view.outside = view.outside || point[i].get_Z() <= 0 || truth.get_u() < 0 || truth.get_v() < 0 ||
                   truth.get_u() > width - 1 || truth.get_v() > height - 1;
    view.observed.emplace_back(i, vpImagePoint(truth.get_i() + noise(), truth.get_j() + noise()));
  }
  return view;
}

// ---- The run's record ----

/*! How a run of servo_ibvs_4pts or servo_pioneer_pan goes: what its last two lines report. */
struct PointServoRun {
  bool converged = false;                     //!< the true error fell under 0.5 px
  std::string reason = "max_iterations";      //!< why it diverged
  int iterations = 0;                         //!< periods run
  double final_error = 0.0;                   //!< true mean corner error at the end (px)
  double path_length = 0.0;                   //!< the camera's path (m)
  double depth_error = 0.0, depth_bias = 0.0; //!< last period: mean |Z used - Z true| / Z true, mean (Z used - Z true) / Z true
  vpTranslationVector centre;                 //!< the camera's centre at the last period

  /*! The camera's start wMc: where its path begins. */
  void start(const vpHomogeneousMatrix &wMc) { centre = wMc.getTranslationVector(); }
  /*! The camera now at wMc: its move since the last period added to the path. */
  void moveTo(const vpHomogeneousMatrix &wMc)
  {
    path_length += (wMc.getTranslationVector() - centre).frobeniusNorm();
    centre = wMc.getTranslationVector();
  }
  /*! The period's view: its true error kept; true when the run ends there (a corner left the image: diverged; the error under 0.5 px: converged). */
  bool ends(const SquareView &view)
  {
    final_error = view.error;
    if (view.outside)
      reason = "feature_left_image";
    else if (view.error < 0.5)
      converged = true;
    return view.outside || converged;
  }
  /*! Starts the period's depth errors. */
  void clearDepthErrors() { depth_error = depth_bias = 0.0; }
  /*! One corner's depth: Z given to the control law against its true depth. */
  void addDepth(double Z, double Z_true)
  {
    depth_error += std::fabs(Z - Z_true) / Z_true / 4.0;
    depth_bias += (Z - Z_true) / Z_true / 4.0;
  }
};

// ---- The printed lines ----

/*!
  The progress line every 50 iterations (every 10 with --verbose, none with --quiet): the
  iteration, the true error, the path, the depths used and the true ones; verbose and estimated
  depth, a line per corner with its estimate.
*/
inline void printProgress(const PointServoArgs &args, const PointServoRun &run, double error,
                          const vpFeaturePoint (&p)[4], const vpPoint (&point)[4],
                          const yawdepth::DepthProvider &provider)
{
  if (args.quiet || run.iterations % (args.verbose ? 10 : 50) != 0)
    return;
  std::printf("it %4d  error %8.3f px  path %.4f  Z used", run.iterations, error, run.path_length);
  for (unsigned i = 0; i < 4; i++)
    std::printf(" %.3f", p[i].get_Z());
  std::printf("  (true");
  for (unsigned i = 0; i < 4; i++)
    std::printf(" %.3f", point[i].get_Z());
  std::printf(")\n");
  if (args.verbose && args.depth_mode == "estimated")
    for (unsigned i = 0; i < 4; i++) {
      const yawdepth::FeatureDepth f = provider.info(i);
      std::printf("    %u: %s estimate %.4f +- %.4f%s\n", i, yawdepth::toString(f.status), f.estimate,
                  f.estimate_sigma, f.converged ? " (used)" : "");
    }
}

/*!
  The last line of every servo example, "converged iterations=N final_error=E" or "diverged
  iterations=N final_error=E reason=R"; returns the exit code (0 converged, 3 diverged).
*/
inline int printOutcome(bool converged, int iterations, double final_error, const std::string &reason)
{
  if (converged) {
    std::printf("converged iterations=%d final_error=%.4f\n", iterations, final_error);
    return 0;
  }
  std::printf("diverged iterations=%d final_error=%.4f reason=%s\n", iterations, final_error, reason.c_str());
  return 3;
}

} // namespace servo_sim
