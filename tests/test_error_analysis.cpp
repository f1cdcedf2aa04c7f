// The paper's Section 4 error analysis, computed from the first-order model.
#include <catch2/catch.hpp>

#include <yawdepth/error.h>
#include <yawdepth/estimation/error_analysis.h>

using namespace yawdepth;

TEST_CASE("the Section 4 table is reproduced term by term", "[error-analysis]")
{
  struct Expect {
    const char *view;
    double depth, u_offset;
    const char *odo, *yaw, *pixel, *parallax, *total;
  };
  // docs/method.md's table; for the side view at 1000 mm the paper prints 0.0001 for the yaw term,
  // the first-order model gives 2.6e-5 (docs/method.md says so); the total is 5.30 % either way.
  const Expect rows[] = {
      {"front", 0.5, 10, "0.05", "0.1484", "0.01", "0.25", "45.84 %"},
      {"front", 0.5, 20, "0.05", "0.0742", "0.005", "0.125", "25.42 %"},
      {"front", 0.5, 50, "0.05", "0.0297", "0.002", "0.05", "13.17 %"},
      {"front", 1.0, 50, "0.05", "0.0297", "0.002", "0.1", "18.17 %"},
      {"side", 0.5, 10, "0.05", "5.1333e-6", "0", "0.0015", "5.15 %"},
      {"side", 1.0, 50, "0.05", "2.5667e-5", "0", "0.0029", "5.30 %"},
  };
  const auto cases = paperErrorCases();
  REQUIRE(cases.size() == 7);
  for (std::size_t i = 0; i < 6; ++i) {
    const Expect &x = rows[i];
    const PaperErrorRow &row = cases[i];
    INFO(x.view << " " << x.depth << " " << x.u_offset);
    REQUIRE(row.view == x.view);
    REQUIRE(row.input.depth == x.depth);
    REQUIRE(row.input.u_offset == x.u_offset);
    const DepthErrorTerms t = firstOrderDepthError(row.input);
    CHECK(formatPaperTerm(t.odometry) == x.odo);
    CHECK(formatPaperTerm(t.yaw) == x.yaw);
    CHECK(formatPaperTerm(t.pixel) == x.pixel);
    CHECK(formatPaperTerm(t.parallax) == x.parallax);
    CHECK(formatPercent(t.total) == x.total);
  }
  // Lateral, eq. (17): du = 0.1 px, u_i - u0 = 50 px, dZ/Z = 0.05 -> 0.15 %.
  const PaperErrorRow &lat = cases[6];
  CHECK(lat.view == "lateral");
  CHECK(formatPercent(lateralRelativeError(lat.input.delta_u, lat.input.kx, lat.input.u_offset,
                                           lat.lateral_depth_error)) == "0.15 %");
}

TEST_CASE("eq. (9) parallax and the general model at intermediate yaw", "[error-analysis]")
{
  ErrorAnalysisCase c;
  c.depth = 0.5;
  c.u_offset = 10;
  CHECK(firstOrderDepthError(c).parallax_px == Approx(0.4).epsilon(1e-12));
  c.yaw = M_PI / 2;
  CHECK(firstOrderDepthError(c).parallax_px == Approx(68.0).epsilon(1e-12));
  // Oblique view lies between: its parallax term is smaller than the front view's.
  c.yaw = M_PI / 4;
  const DepthErrorTerms oblique = firstOrderDepthError(c);
  c.yaw = 0;
  CHECK(oblique.total < firstOrderDepthError(c).total);
}

TEST_CASE("formatting follows the paper's rounding", "[error-analysis]")
{
  CHECK(formatPaperTerm(0.05) == "0.05");
  CHECK(formatPaperTerm(0.14835) == "0.1484");
  CHECK(formatPaperTerm(0.0014706) == "0.0015");
  CHECK(formatPaperTerm(5.13329e-6) == "5.1333e-6");
  CHECK(formatPaperTerm(9.999996e-5) == "1.0000e-4");
  CHECK(formatPaperTerm(0.0) == "0");
  CHECK(formatPercent(0.458397) == "45.84 %");
}

TEST_CASE("the 1-sigma first-order error agrees with Monte Carlo where first order holds", "[error-analysis]")
{
  ErrorAnalysisCase c; // side view, good parallax: first order is accurate
  c.yaw = M_PI / 2;
  c.depth = 1.0;
  c.u_offset = 50;
  const MonteCarloDepthError mc = monteCarloDepthError(c, 200000, 7);
  CHECK(mc.rms_relative == Approx(firstOrderDepthSigma(c)).epsilon(0.03));
  CHECK(std::abs(mc.bias_relative) < 0.01);
  // Same seed, same numbers.
  CHECK(monteCarloDepthError(c, 1000, 3).rms_relative == monteCarloDepthError(c, 1000, 3).rms_relative);
}

TEST_CASE("invalid error-analysis input is rejected", "[error-analysis]")
{
  ErrorAnalysisCase c;
  c.depth = -1;
  CHECK_THROWS_AS(firstOrderDepthError(c), Error);
  c = ErrorAnalysisCase();
  c.kx = std::numeric_limits<double>::quiet_NaN();
  CHECK_THROWS_AS(firstOrderDepthError(c), Error);
  c = ErrorAnalysisCase();
  c.u_offset = 0; // front view at the principal point: the focus of expansion
  CHECK_THROWS_AS(firstOrderDepthError(c), Error);
  CHECK_THROWS_AS(monteCarloDepthError(ErrorAnalysisCase(), 0), Error);
}
