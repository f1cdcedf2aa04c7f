// `yawdepth error-analysis`: the paper's Section 4 table, or a user's own case, from the
// first-order model (and optionally a Monte Carlo column).
#include "commands.h"

#include <cmath>
#include <cstdio>
#include <memory>
#include <yawdepth/camera/camera_file.h>
#include <yawdepth/error.h>
#include <yawdepth/estimation/error_analysis.h>

namespace yawdepth::cli {

namespace {

struct ErrorArgs {
  bool paper = false, quiet = false;
  std::string camera, camera_name; // --camera: kx is its px
  ErrorAnalysisCase c;
  int monte_carlo = 0;
  unsigned long long seed = 1;
};

void printHeader(bool mc)
{
  std::printf("%-8s %7s %11s %16s %9s %11s %9s %9s %9s", "view", "Z(mm)", "u_i-u0(px)", "u_i-u_i-1(px)",
              "odometry", "yaw", "pixel", "parallax", "total");
  if (mc)
    std::printf(" %11s %11s %11s", "1sigma_fo", "mc_rms", "mc_median");
  std::printf("\n");
}

void printRow(const std::string &view, const ErrorAnalysisCase &c, int mc, unsigned long long seed)
{
  const DepthErrorTerms t = firstOrderDepthError(c);
  char parallax[32];
  std::snprintf(parallax, sizeof parallax, "%.4g", t.parallax_px);
  std::printf("%-8s %7.0f %11.4g %16s %9s %11s %9s %9s %9s", view.c_str(), c.depth * 1000.0, c.u_offset, parallax,
              formatPaperTerm(t.odometry).c_str(), formatPaperTerm(t.yaw).c_str(), formatPaperTerm(t.pixel).c_str(),
              formatPaperTerm(t.parallax).c_str(), formatPercent(t.total).c_str());
  if (mc > 0) {
    const MonteCarloDepthError r = monteCarloDepthError(c, mc, seed);
    std::printf(" %11s %11s %11s", formatPercent(firstOrderDepthSigma(c)).c_str(),
                formatPercent(r.rms_relative).c_str(), formatPercent(r.median_abs_relative).c_str());
  }
  std::printf("\n");
}

/* --kx, or --camera (and --camera-name) whose px gives it: the two exclude each other. */
void addErrorAnalysisCameraOptions(CLI::App *sub, ErrorArgs &a)
{
  CLI::Option *kx = sub->add_option("--kx", a.c.kx, "Focal length (px)")->check(Finite)->capture_default_str();
  addCameraOptions(sub, a.camera, a.camera_name, false, "kx is its px, instead of --kx")->excludes(kx);
  sub->get_option("--camera-name")->needs("--camera");
}

} // namespace

Runner addErrorAnalysis(CLI::App &app)
{
  auto a = std::make_shared<ErrorArgs>();
  CLI::App *sub = app.add_subcommand(
      "error-analysis",
      "First-order depth error of eq. (9) (the paper's Section 4): the paper's table with --paper, or your own case.");
  sub->add_flag("--paper", a->paper, "Print the paper's Section 4 table (computed, not stored)");
  auto *yaw = sub->add_option("--yaw", a->c.yaw, "Camera yaw theta (rad): 0 front view, 1.5708 side view")
                  ->check(Finite)
                  ->capture_default_str();
  sub->add_option_function<std::string>(
         "--view", [a](const std::string &v) { a->c.yaw = v == "side" ? M_PI / 2 : v == "oblique" ? M_PI / 4 : 0.0; },
         "Shorthand for --yaw: front (0 rad), oblique (pi/4 = 0.7854 rad) or side (pi/2 = 1.5708 rad)")
      ->check(CLI::IsMember({"front", "oblique", "side"}))
      ->excludes(yaw);
  sub->add_option("--depth", a->c.depth, "Depth Z (m)")->check(Finite)->capture_default_str();
  sub->add_option("--u-offset", a->c.u_offset, "u_i - u0 (px)")->check(Finite)->capture_default_str();
  sub->add_option("--dz", a->c.dz, "Forward increment (m)")->check(Finite)->capture_default_str();
  addErrorAnalysisCameraOptions(sub, *a);
  // The noise takes the names the other commands give it; the paper's delta names stay as aliases.
  renamedFrom(sub,
              sub->add_option("--sigma-odom,--delta-dz", a->c.delta_dz, "Odometry error of the increment (m)")
                  ->check(FiniteNonNegative)
                  ->capture_default_str(),
              "--delta-dz");
  renamedFrom(sub,
              sub->add_option("--sigma-yaw,--delta-yaw", a->c.delta_yaw, "Yaw reading error (rad)")
                  ->check(FiniteNonNegative)
                  ->capture_default_str(),
              "--delta-yaw");
  renamedFrom(sub,
              sub->add_option("--sigma-px,--delta-u", a->c.delta_u,
                              "Pixel error of u_i (px); the Monte Carlo noise per reading")
                  ->check(FiniteNonNegative)
                  ->capture_default_str(),
              "--delta-u");
  sub->add_option("--delta-du", a->c.delta_du, "|du_i - du_{i-1}| (px)")->check(FiniteNonNegative)->capture_default_str();
  sub->add_option("--monte-carlo", a->monte_carlo,
                  "Also print the 1-sigma first-order error and a Monte Carlo RMS and median over N draws")
      ->check(CLI::Range(0, 100000000));
  sub->add_option("--seed", a->seed, "Monte Carlo seed")->capture_default_str();
  addVerbosityOptions(sub, a->quiet, "Nothing to silence: the table is the only output");

  return [a]() {
    if (a->paper) {
      const ErrorAnalysisCase defaults;
      std::printf("Section 4 error analysis: first-order relative depth error, eqs. (9)-(14)\n");
      std::printf("inputs: dz = %g mm, kx = %g px, ddz = %g mm, dtheta = %g deg, du_i = %g px, "
                  "|du_i - du_i-1| = %g px\n\n",
                  defaults.dz * 1e3, defaults.kx, defaults.delta_dz * 1e3, defaults.delta_yaw * 180.0 / M_PI,
                  defaults.delta_u, defaults.delta_du);
      printHeader(a->monte_carlo > 0);
      double lateral_du = 0, lateral_offset = 0, lateral_dz = 0, lateral_kx = 0;
      for (const PaperErrorRow &row : paperErrorCases()) {
        if (row.view == "lateral") {
          lateral_du = row.input.delta_u;
          lateral_offset = row.input.u_offset;
          lateral_dz = row.lateral_depth_error;
          lateral_kx = row.input.kx;
          continue;
        }
        printRow(row.view, row.input, a->monte_carlo, a->seed);
      }
      const double pix = lateral_du / lateral_kx, prop = std::abs(lateral_offset) / lateral_kx * lateral_dz;
      std::printf("\nlateral, eq. (17): u_i-u0 = %g px, du_i = %g px, dZc/Zc = %s: du_i/kx = %s, "
                  "(u_i-u0)/kx * dZc/Zc = %s, dXc/Zc = %s\n",
                  lateral_offset, lateral_du, formatPaperTerm(lateral_dz).c_str(), formatPaperTerm(pix).c_str(),
                  formatPaperTerm(prop).c_str(),
                  formatPercent(lateralRelativeError(lateral_du, lateral_kx, lateral_offset, lateral_dz)).c_str());
      std::printf("\nTotals are the paper's (sum of absolute terms). In the side-view row at 1000 mm the paper "
                  "prints 0.0001 for the yaw term; the first-order model gives the value above.\n");
      return 0;
    }
    if (!a->camera.empty())
      a->c.kx = loadCameraFile(a->camera, a->camera_name).kx();
    a->c.validate();
    printHeader(a->monte_carlo > 0);
    char view[32];
    std::snprintf(view, sizeof view, "%.4g", a->c.yaw * 180.0 / M_PI);
    printRow(std::string("yaw") + view, a->c, a->monte_carlo, a->seed);
    return 0;
  };
}

} // namespace yawdepth::cli
