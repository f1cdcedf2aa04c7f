#include <yawdepth/estimation/error_analysis.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <yawdepth/error.h>

namespace yawdepth {

namespace {

/* N = (u_i - u0) cos(theta) + kx sin(theta) and its derivatives. */
struct Numerator {
  double N, dN_dtheta, dN_du;
};

Numerator numerator(const ErrorAnalysisCase &c, double yaw, double u_offset)
{
  const double co = std::cos(yaw), si = std::sin(yaw);
  return {u_offset * co + c.kx * si, c.kx * co - u_offset * si, co};
}

void require(bool ok, const char *what)
{
  if (!ok)
    throw Error(what);
}

} // namespace

void ErrorAnalysisCase::validate() const
{
  for (double v : {yaw, depth, u_offset, dz, kx, delta_dz, delta_yaw, delta_u, delta_du})
    require(std::isfinite(v), "error-analysis: every input must be a finite number");
  require(depth > 0, "error-analysis: depth must be positive");
  require(dz > 0, "error-analysis: dz must be positive");
  require(kx > 0, "error-analysis: kx must be positive");
  require(delta_dz >= 0 && delta_yaw >= 0 && delta_u >= 0 && delta_du >= 0,
          "error-analysis: errors must be non-negative");
  // Rounding cos(pi/2) leaves ~1e-14 px of numerator; anything below that is the focus of expansion.
  require(std::abs(numerator(*this, yaw, u_offset).N) > 1e-9 * kx,
          "error-analysis: the feature is at the focus of expansion (no parallax): depth is unobservable");
}

DepthErrorTerms firstOrderDepthError(const ErrorAnalysisCase &c)
{
  c.validate();
  const Numerator n = numerator(c, c.yaw, c.u_offset);
  DepthErrorTerms t;
  t.parallax_px = c.dz * n.N / c.depth; // D from eq. (9)
  t.odometry = c.delta_dz / c.dz;
  t.yaw = std::abs(n.dN_dtheta) * c.delta_yaw / std::abs(n.N);
  // cos(pi/2) is 6e-17 in floating point: a term below round-off of the numerator is zero.
  t.pixel = std::abs(n.dN_du) < 1e-12 ? 0.0 : std::abs(n.dN_du) * c.delta_u / std::abs(n.N);
  t.parallax = c.delta_du / std::abs(t.parallax_px);
  t.total = t.odometry + t.yaw + t.pixel + t.parallax;
  return t;
}

double firstOrderDepthSigma(const ErrorAnalysisCase &c)
{
  c.validate();
  const Numerator n = numerator(c, c.yaw, c.u_offset);
  const double D = c.dz * n.N / c.depth;
  // ln Z = ln dz + ln N(u_i, theta) - ln(u_i - u_{i-1})
  const double g_dz = 1.0 / c.dz, g_th = n.dN_dtheta / n.N;
  const double g_ui = n.dN_du / n.N - 1.0 / D, g_uim1 = 1.0 / D;
  const double s_u = c.delta_u;
  return std::sqrt(std::pow(g_dz * c.delta_dz, 2) + std::pow(g_th * c.delta_yaw, 2) +
                   s_u * s_u * (g_ui * g_ui + g_uim1 * g_uim1));
}

double lateralRelativeError(double delta_u, double kx, double u_offset, double depth_relative_error)
{
  require(std::isfinite(delta_u) && std::isfinite(kx) && std::isfinite(u_offset) && std::isfinite(depth_relative_error),
          "error-analysis: every input must be a finite number");
  require(kx > 0, "error-analysis: kx must be positive");
  return std::abs(delta_u) / kx + std::abs(u_offset) / kx * std::abs(depth_relative_error);
}

MonteCarloDepthError monteCarloDepthError(const ErrorAnalysisCase &c, int samples, std::uint64_t seed)
{
  c.validate();
  require(samples > 0, "error-analysis: the number of Monte Carlo samples must be positive");
  const double D = c.dz * numerator(c, c.yaw, c.u_offset).N / c.depth;
  // Pixel coordinates relative to u0: u_i - u0 and u_{i-1} - u0.
  const double ui = c.u_offset, uim1 = c.u_offset - D;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  std::vector<double> rel;
  rel.reserve(static_cast<std::size_t>(samples));
  double sum = 0, sum2 = 0;
  for (int k = 0; k < samples; ++k) {
    const double dz = c.dz + c.delta_dz * g(rng);
    const double th = c.yaw + c.delta_yaw * g(rng);
    const double u1 = ui + c.delta_u * g(rng);
    const double u0 = uim1 + c.delta_u * g(rng);
    const double Z = dz * numerator(c, th, u1).N / (u1 - u0);
    const double e = (Z - c.depth) / c.depth;
    rel.push_back(std::abs(e));
    sum += e;
    sum2 += e * e;
  }
  MonteCarloDepthError r;
  r.samples = samples;
  r.bias_relative = sum / samples;
  r.rms_relative = std::sqrt(sum2 / samples);
  std::nth_element(rel.begin(), rel.begin() + samples / 2, rel.end());
  r.median_abs_relative = rel[static_cast<std::size_t>(samples / 2)];
  return r;
}

std::vector<PaperErrorRow> paperErrorCases()
{
  const double side = M_PI / 2;
  std::vector<PaperErrorRow> rows;
  auto add = [&rows](const char *view, double yaw, double depth, double u_offset) {
    PaperErrorRow r;
    r.view = view;
    r.input.yaw = yaw;
    r.input.depth = depth;
    r.input.u_offset = u_offset;
    rows.push_back(r);
  };
  add("front", 0.0, 0.5, 10);
  add("front", 0.0, 0.5, 20);
  add("front", 0.0, 0.5, 50);
  add("front", 0.0, 1.0, 50);
  add("side", side, 0.5, 10);
  add("side", side, 1.0, 50);
  add("lateral", 0.0, 0.5, 50);
  rows.back().lateral_depth_error = 0.05;
  return rows;
}

std::string formatPaperTerm(double v)
{
  char buf[64];
  if (v == 0.0)
    return "0";
  if (std::abs(v) < 5e-4) {
    int exponent = static_cast<int>(std::floor(std::log10(std::abs(v))));
    double mantissa = v / std::pow(10.0, exponent);
    if (std::abs(mantissa) >= 9.99995) { // rounding carries into the next power of ten
      mantissa /= 10;
      ++exponent;
    }
    std::snprintf(buf, sizeof buf, "%.4fe%d", mantissa, exponent);
    return buf;
  }
  std::snprintf(buf, sizeof buf, "%.4f", v);
  std::string s = buf;
  while (!s.empty() && s.back() == '0')
    s.pop_back();
  if (!s.empty() && s.back() == '.')
    s.pop_back();
  return s;
}

std::string formatPercent(double v)
{
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.2f %%", 100.0 * v);
  return buf;
}

} // namespace yawdepth
