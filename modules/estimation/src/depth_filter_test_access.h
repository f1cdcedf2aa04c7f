#pragma once
/*
  depth_filter_test_access.h: the filter's raw state (x, y, lambda, e) and its covariance, private to
  DepthFilter (users read the point through estimate(), depth() and logDepthSigma()), for the tests
  that check the prediction against finite differences. Not installed; tests reach it through the
  module's src/ directory.
*/
#include <Eigen/Core>
#include <yawdepth/estimation/depth_filter.h>

namespace yawdepth {

struct DepthFilterTestAccess {
  static const Eigen::Vector4d &state(const DepthFilter &f) { return f.s_; }
  static const Eigen::Matrix4d &covariance(const DepthFilter &f) { return f.P_; }
};

} // namespace yawdepth
