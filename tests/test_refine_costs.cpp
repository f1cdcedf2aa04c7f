// refine's Ceres cost functors (modules/refine/src/costs/, private; built with Ceres only): for
// every functor, at seeded random parameter points, the Jacobians Ceres computes by automatic
// differentiation against central differences of the residual, and the residual at the truth
// (zero, or the whitened offset a measurement was given).
// The functors' headers come before Catch: Ceres brings glog, whose CHECK macro would otherwise
// replace Catch's.
#include "costs/innovation_costs.h"
#include "costs/observation_costs.h"
#include "costs/odometry_costs.h"
#include "costs/prior_costs.h"
#undef CHECK

#include <catch2/catch.hpp>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <memory>
#include <random>
#include <vector>
#include <yawdepth/geometry/rig.h>

using namespace yawdepth;
using namespace yawdepth::refine_detail;

namespace {

constexpr int kPoints = 6;                   // random parameter points per functor
constexpr double kStep = 1e-6;               // central-difference step (parameters are O(1))
constexpr double kJacobianTolerance = 1e-6;  // |autodiff - central difference| / (1 + |autodiff|)
constexpr double kZeroTolerance = 1e-9;      // a residual at the truth (whitening scales are ~500)
constexpr double kWhitenedTolerance = 1e-12; // a prior's residual one sigma off its measurement (1)

using Blocks = std::vector<std::vector<double>>;

std::vector<const double *> pointersTo(const Blocks &blocks)
{
  std::vector<const double *> p;
  for (const auto &b : blocks)
    p.push_back(b.data());
  return p;
}

/* The cost's residual at the blocks; REQUIREs that Ceres evaluates it. */
std::vector<double> residualOf(const ceres::CostFunction &cost, const Blocks &blocks)
{
  std::vector<double> r(static_cast<std::size_t>(cost.num_residuals()));
  const std::vector<const double *> p = pointersTo(blocks);
  REQUIRE(cost.Evaluate(p.data(), r.data(), nullptr));
  return r;
}

/* Ceres's Jacobian of every block (row-major, residuals x block size) against central differences
   of the residual, entry by entry. */
void checkJacobians(const ceres::CostFunction &cost, Blocks blocks)
{
  const std::size_t m = static_cast<std::size_t>(cost.num_residuals());
  const std::vector<int32_t> &sizes = cost.parameter_block_sizes();
  REQUIRE(sizes.size() == blocks.size());
  std::vector<std::vector<double>> jac(blocks.size());
  std::vector<double *> jac_ptr;
  for (std::size_t b = 0; b < blocks.size(); ++b) {
    REQUIRE(blocks[b].size() == static_cast<std::size_t>(sizes[b]));
    jac[b].assign(m * blocks[b].size(), 0.0);
    jac_ptr.push_back(jac[b].data());
  }
  std::vector<double> r(m);
  const std::vector<const double *> p = pointersTo(blocks);
  REQUIRE(cost.Evaluate(p.data(), r.data(), jac_ptr.data()));
  for (std::size_t b = 0; b < blocks.size(); ++b)
    for (std::size_t j = 0; j < blocks[b].size(); ++j) {
      const double x = blocks[b][j];
      blocks[b][j] = x + kStep;
      const std::vector<double> up = residualOf(cost, blocks);
      blocks[b][j] = x - kStep;
      const std::vector<double> down = residualOf(cost, blocks);
      blocks[b][j] = x;
      for (std::size_t i = 0; i < m; ++i) {
        const double by_ceres = jac[b][i * blocks[b].size() + j];
        const double by_differences = (up[i] - down[i]) / (2 * kStep);
        INFO("block " << b << ", parameter " << j << ", residual " << i << ": autodiff " << by_ceres
                      << ", central difference " << by_differences);
        CHECK(std::abs(by_ceres - by_differences) <= kJacobianTolerance * (1.0 + std::abs(by_ceres)));
      }
    }
}

void checkZero(const std::vector<double> &r)
{
  for (double v : r)
    CHECK(std::abs(v) <= kZeroTolerance);
}

/* Random numbers for the scenes: seeded, so that every run checks the same points. */
struct Draw {
  explicit Draw(std::uint64_t seed) : rng(seed) {}
  double operator()(double half_width) { return half_width * U(rng); }
  std::mt19937_64 rng;
  std::uniform_real_distribution<double> U{-1.0, 1.0};
};

/* A whitening near diag(500, 500) px / (normalised unit), as sigma_px = 1 on a 500 px focal length. */
WhitenedObservation whitening(Draw &draw)
{
  WhitenedObservation w;
  w.s00 = 500 + draw(100);
  w.s01 = draw(50);
  w.s11 = 500 + draw(100);
  return w;
}

/* A point anchored in the anchor frame's camera: (alpha, beta) within the view, depth 1.3 to 3.3 m. */
std::vector<double> anchoredPointOf(Draw &draw) { return {draw(0.3), draw(0.2), 0.5 + draw(0.2)}; }

/* Planar frame blocks (x, y, z, heading, yaw) a few centimetres and degrees apart. */
std::vector<double> planarFrame(Draw &draw) { return {draw(0.1), draw(0.01), draw(0.1), draw(0.1), draw(0.1)}; }

/* General frame blocks (x, y, z, dx, dy, dz, yaw) about their rows' reference orientations. */
std::vector<double> generalFrame(Draw &draw)
{
  return {draw(0.1), draw(0.02), draw(0.1), draw(0.02), draw(0.1), draw(0.02), draw(0.1)};
}

Eigen::Matrix3d referenceOrientation(Draw &draw, const Eigen::Matrix3d &near, double spread)
{
  return near * expSO3<double>(Eigen::Vector3d(draw(spread), draw(spread), draw(spread)));
}

Mount mountOf(Draw &draw)
{
  Mount mount;
  mount.R0 = expSO3<double>(Eigen::Vector3d(0.1 + draw(0.05), -0.2 + draw(0.05), 1.5 + draw(0.05)));
  mount.t0 = Eigen::Vector3d(0.05 + draw(0.01), -0.03 + draw(0.01), -0.04 + draw(0.01));
  return mount;
}

/* The observation a planar frame makes of the point with no error (m its projection). */
WhitenedObservation seenPlanar(WhitenedObservation w, const std::vector<double> &fa, const std::vector<double> &fk,
                               const std::vector<double> &point, const double *t0)
{
  double q[3];
  anchoredPoint(fa.data(), fa.data() + 4, fk.data(), fk.data() + 4, point.data(), t0, q);
  REQUIRE(q[2] > 0);
  w.m[0] = q[0] / q[2];
  w.m[1] = q[1] / q[2];
  return w;
}

/* The same, general chain. */
WhitenedObservation seenGeneral(WhitenedObservation w, const std::vector<double> &fa, const Eigen::Matrix3d &Rref_a,
                                const std::vector<double> &fk, const Eigen::Matrix3d &Rref_k,
                                const std::vector<double> &point, const Mount &mount)
{
  double q[3];
  anchoredPointGeneral(fa.data(), Rref_a, fk.data(), Rref_k, point.data(), mount, q);
  REQUIRE(q[2] > 0);
  w.m[0] = q[0] / q[2];
  w.m[1] = q[1] / q[2];
  return w;
}

/* The anchor frame's own observation with no error. */
WhitenedObservation seenAtAnchor(WhitenedObservation w, const std::vector<double> &point)
{
  w.m[0] = point[0];
  w.m[1] = point[1];
  return w;
}

/* Each value of each block moved by up to `amount` (small enough that a point stays in front). */
Blocks moved(Blocks blocks, Draw &draw, double amount)
{
  for (auto &b : blocks)
    for (double &v : b)
      v += draw(amount);
  return blocks;
}

} // namespace

TEST_CASE("refine's observation functors: autodiff Jacobians against central differences, zero at the truth",
          "[refine][costs]")
{
  Draw draw(101);
  const double t0[3] = {-0.1503, 0.01, 0.02};
  for (int k = 0; k < kPoints; ++k) {
    const std::vector<double> fa = planarFrame(draw), fk = planarFrame(draw), point = anchoredPointOf(draw);
    const WhitenedObservation w = seenPlanar(whitening(draw), fa, fk, point, t0);
    const std::unique_ptr<ceres::CostFunction> reprojection(ReprojectionCost::Create(w, t0));
    checkZero(residualOf(*reprojection, {fa, fk, point}));
    checkJacobians(*reprojection, moved({fa, fk, point}, draw, 0.02));

    const std::unique_ptr<ceres::CostFunction> anchor(AnchorCost::Create(seenAtAnchor(whitening(draw), point)));
    checkZero(residualOf(*anchor, {point}));
    checkJacobians(*anchor, moved({point}, draw, 0.02));

    const Mount mount = mountOf(draw);
    const Eigen::Matrix3d Ra = referenceOrientation(draw, Eigen::Matrix3d::Identity(), 1.0);
    const Eigen::Matrix3d Rk = referenceOrientation(draw, Ra, 0.1);
    const std::vector<double> ga = generalFrame(draw), gk = generalFrame(draw);
    const std::vector<double> point_g = {point[0], point[1], 0.6 + draw(0.1)};
    const WhitenedObservation wg = seenGeneral(whitening(draw), ga, Ra, gk, Rk, point_g, mount);
    const std::unique_ptr<ceres::CostFunction> general(ReprojectionCostGeneral::Create(wg, Ra, Rk, mount));
    checkZero(residualOf(*general, {ga, gk, point_g}));
    checkJacobians(*general, moved({ga, gk, point_g}, draw, 0.02));
  }
}

TEST_CASE("refine's innovation functors: autodiff Jacobians against central differences, zero at the truth",
          "[refine][costs][correlated]")
{
  Draw draw(202);
  const double t0[3] = {-0.1503, 0.01, 0.02};
  for (int k = 0; k < kPoints; ++k) {
    const ChainCoefficient c(0.5 + draw(0.4)); // phi^gap
    const std::vector<double> fa = planarFrame(draw), fp = planarFrame(draw), fk = planarFrame(draw);
    const std::vector<double> point = anchoredPointOf(draw);
    const WhitenedObservation at_anchor = seenAtAnchor(whitening(draw), point);
    const WhitenedObservation prev = seenPlanar(whitening(draw), fa, fp, point, t0);
    const WhitenedObservation cur = seenPlanar(whitening(draw), fa, fk, point, t0);
    const std::unique_ptr<ceres::CostFunction> after_anchor(
        InnovationAfterAnchorCost::Create(at_anchor, cur, t0, c));
    checkZero(residualOf(*after_anchor, {fa, fk, point}));
    checkJacobians(*after_anchor, moved({fa, fk, point}, draw, 0.02));
    const std::unique_ptr<ceres::CostFunction> innovation(InnovationCost::Create(prev, cur, t0, c));
    checkZero(residualOf(*innovation, {fa, fp, fk, point}));
    checkJacobians(*innovation, moved({fa, fp, fk, point}, draw, 0.02));

    const Mount mount = mountOf(draw);
    const Eigen::Matrix3d Ra = referenceOrientation(draw, Eigen::Matrix3d::Identity(), 1.0);
    const Eigen::Matrix3d Rp = referenceOrientation(draw, Ra, 0.1), Rk = referenceOrientation(draw, Ra, 0.1);
    const std::vector<double> ga = generalFrame(draw), gp = generalFrame(draw), gk = generalFrame(draw);
    const std::vector<double> point_g = {point[0], point[1], 0.6 + draw(0.1)};
    const WhitenedObservation at_anchor_g = seenAtAnchor(whitening(draw), point_g);
    const WhitenedObservation prev_g = seenGeneral(whitening(draw), ga, Ra, gp, Rp, point_g, mount);
    const WhitenedObservation cur_g = seenGeneral(whitening(draw), ga, Ra, gk, Rk, point_g, mount);
    const std::unique_ptr<ceres::CostFunction> after_anchor_g(
        InnovationAfterAnchorCostGeneral::Create(at_anchor_g, cur_g, Ra, Rk, mount, c));
    checkZero(residualOf(*after_anchor_g, {ga, gk, point_g}));
    checkJacobians(*after_anchor_g, moved({ga, gk, point_g}, draw, 0.02));
    const std::unique_ptr<ceres::CostFunction> innovation_g(
        InnovationCostGeneral::Create(prev_g, cur_g, Ra, Rp, Rk, mount, c));
    checkZero(residualOf(*innovation_g, {ga, gp, gk, point_g}));
    checkJacobians(*innovation_g, moved({ga, gp, gk, point_g}, draw, 0.02));
  }
}

TEST_CASE("refine's odometry functors: autodiff Jacobians against central differences, zero at the truth",
          "[refine][costs]")
{
  Draw draw(303);
  for (int k = 0; k < kPoints; ++k) {
    // Planar: d = Ry(heading_prev)^T (p_cur - p_prev), dh = heading_cur - heading_prev.
    const std::vector<double> prev = planarFrame(draw), cur = planarFrame(draw);
    OdometryMeasurement o;
    const Eigen::Vector3d d =
        rotY(prev[3]).transpose() * Eigen::Vector3d(cur[0] - prev[0], cur[1] - prev[1], cur[2] - prev[2]);
    for (int i = 0; i < 3; ++i)
      o.d[i] = d(i);
    o.dh = cur[3] - prev[3];
    o.inv_sigma_t = 1.0 / (0.01 + draw(0.005));
    o.inv_sigma_h = 1.0 / (0.005 + draw(0.002));
    const std::unique_ptr<ceres::CostFunction> planar(OdometryCost::Create(o));
    checkZero(residualOf(*planar, {prev, cur}));
    checkJacobians(*planar, moved({prev, cur}, draw, 0.05));

    // General: d = Rp^T (p_cur - p_prev), dR = Rp^T Rc, R = Rref Exp(d).
    const std::vector<double> gprev = generalFrame(draw), gcur = generalFrame(draw);
    OdometryMeasurementGeneral og;
    og.Rref_prev = referenceOrientation(draw, Eigen::Matrix3d::Identity(), 1.0);
    og.Rref_cur = referenceOrientation(draw, og.Rref_prev, 0.1);
    const Eigen::Matrix3d Rp = og.Rref_prev * expSO3<double>(Eigen::Vector3d(gprev[3], gprev[4], gprev[5]));
    const Eigen::Matrix3d Rc = og.Rref_cur * expSO3<double>(Eigen::Vector3d(gcur[3], gcur[4], gcur[5]));
    const Eigen::Vector3d dg = Rp.transpose() * Eigen::Vector3d(gcur[0] - gprev[0], gcur[1] - gprev[1], gcur[2] - gprev[2]);
    for (int i = 0; i < 3; ++i) {
      og.d[i] = dg(i);
      og.inv_sigma_r[i] = 1.0 / (0.004 + draw(0.002));
    }
    og.dR = Rp.transpose() * Rc;
    og.inv_sigma_t = 1.0 / (0.01 + draw(0.005));
    const std::unique_ptr<ceres::CostFunction> general(OdometryCostGeneral::Create(og));
    checkZero(residualOf(*general, {gprev, gcur}));
    checkJacobians(*general, moved({gprev, gcur}, draw, 0.05));
  }
}

TEST_CASE("refine's prior functors: autodiff Jacobians against central differences, whitened values",
          "[refine][costs]")
{
  Draw draw(404);
  for (int k = 0; k < kPoints; ++k) {
    // Yaw reading: zero at the reading, one sigma above it gives 1.
    const std::vector<double> planar = planarFrame(draw), general = generalFrame(draw);
    const double sigma_yaw = 0.01 + draw(0.005);
    const std::unique_ptr<ceres::CostFunction> yaw5(YawCost<5>::Create(planar[4], 1.0 / sigma_yaw));
    const std::unique_ptr<ceres::CostFunction> yaw7(YawCost<7>::Create(general[6], 1.0 / sigma_yaw));
    checkZero(residualOf(*yaw5, {planar}));
    checkZero(residualOf(*yaw7, {general}));
    std::vector<double> planar_up = planar, general_up = general;
    planar_up[4] += sigma_yaw;
    general_up[6] += sigma_yaw;
    CHECK(std::abs(residualOf(*yaw5, {planar_up})[0] - 1.0) <= kWhitenedTolerance);
    CHECK(std::abs(residualOf(*yaw7, {general_up})[0] - 1.0) <= kWhitenedTolerance);
    checkJacobians(*yaw5, moved({planar}, draw, 0.05));
    checkJacobians(*yaw7, moved({general}, draw, 0.05));

    // Per-pose prior: zero at the measured pose, each component one sigma off gives 1 there only.
    PosePrior p4, p6;
    for (int i = 0; i < 6; ++i) {
      p4.value[i] = i < 4 ? planar[static_cast<std::size_t>(i)] : 0.0;
      p6.value[i] = i < 3 ? general[static_cast<std::size_t>(i)] : 0.0; // the rotation is the offset d from Rref
      p4.inv_sigma[i] = p6.inv_sigma[i] = 1.0 / (0.02 + draw(0.01));
    }
    std::vector<double> general_at_prior = general;
    for (int i = 3; i < 6; ++i)
      general_at_prior[static_cast<std::size_t>(i)] = 0.0;
    const std::unique_ptr<ceres::CostFunction> prior4(PosePriorCost<4, 5>::Create(p4));
    const std::unique_ptr<ceres::CostFunction> prior6(PosePriorCost<6, 7>::Create(p6));
    checkZero(residualOf(*prior4, {planar}));
    checkZero(residualOf(*prior6, {general_at_prior}));
    for (int i = 0; i < 4; ++i) {
      std::vector<double> off = planar;
      off[static_cast<std::size_t>(i)] += 1.0 / p4.inv_sigma[i];
      const std::vector<double> r = residualOf(*prior4, {off});
      for (int j = 0; j < 4; ++j)
        CHECK(std::abs(r[static_cast<std::size_t>(j)] - (i == j ? 1.0 : 0.0)) <= kWhitenedTolerance);
    }
    checkJacobians(*prior4, moved({planar}, draw, 0.05));
    checkJacobians(*prior6, moved({general}, draw, 0.05));
  }
}
