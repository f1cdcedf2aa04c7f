#pragma once
/*!
  \file bench_common.h
  \brief What the benchmarks share: the paper's camera and rig, the median and quantiles, and a plain command
  line of "--name value" options. Header-only, not installed.
*/
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <map>
#include <string>
#include <utility>
#include <vector>
#include <Eigen/Core>
#include <yawdepth/camera/camera_model.h>
#include <yawdepth/geometry/rig.h>

namespace yawdepth {
namespace bench {

/*! The paper's camera (Brown, 640x480). */
inline CameraModel paperCamera() {
  return CameraModel::brown(1734.1, 1734.5, 319.2, 241.4, {-0.11042, 0.43607, -0.00084, 0.00035}, 640, 480);
}
/*! The paper's rig (Lb = 150.3 mm). */
inline YawRig paperRig() { return YawRig(Eigen::Vector3d(-0.1503, 0.0, 0.0)); }

/*! \brief Median (NaN when empty). */
inline double median(std::vector<double> v) {
  if (v.empty())
    return std::nan("");
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/*! \brief The q-quantile (0..1, the nearest rank) of `v`; NaN when empty. */
inline double quantile(std::vector<double> v, double q) {
  if (v.empty())
    return std::nan("");
  std::sort(v.begin(), v.end());
  const std::size_t k =
      std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size() - 1) + 0.5));
  return v[k];
}

/*!
  A benchmark's command line: each option a flag ("--name") or a name followed by a fixed number
  of values, bound to a variable or given to a handler; the last of a repeated option wins.
*/
class CommandLine {
public:
  /*! `usage`: the options as the usage line lists them after the program's name. */
  explicit CommandLine(std::string usage) : usage_(std::move(usage)) {}
  /*! --name sets `on`. */
  CommandLine &flag(const std::string &name, bool &on) {
    return option(name, 0, [&on](char **) { on = true; });
  }
  /*! --name N (std::atoi). */
  CommandLine &option(const std::string &name, int &v) {
    return option(name, 1, [&v](char **a) { v = std::atoi(a[0]); });
  }
  /*! --name X (std::atof). */
  CommandLine &option(const std::string &name, double &v) {
    return option(name, 1, [&v](char **a) { v = std::atof(a[0]); });
  }
  /*! --name N (std::strtoull, base 10). */
  CommandLine &option(const std::string &name, std::uint64_t &v) {
    return option(name, 1, [&v](char **a) { v = std::strtoull(a[0], nullptr, 10); });
  }
  /*! --name TEXT. */
  CommandLine &option(const std::string &name, std::string &v) {
    return option(name, 1, [&v](char **a) { v = a[0]; });
  }
  /*! --name V1 .. Vn: `set` gets the n values. */
  CommandLine &option(const std::string &name, int values, std::function<void(char **)> set) {
    options_[name] = Option{values, std::move(set)};
    return *this;
  }
  /*! Reads argv; false, after "usage: PROGRAM USAGE" on stderr, on an unknown option or one short of values. */
  bool parse(int argc, char **argv) const {
    for (int i = 1; i < argc; ++i) {
      const auto o = options_.find(argv[i]);
      if (o == options_.end() || i + o->second.values >= argc) {
        std::fprintf(stderr, "usage: %s %s\n", argv[0], usage_.c_str());
        return false;
      }
      o->second.set(argv + i + 1);
      i += o->second.values;
    }
    return true;
  }

private:
  struct Option {
    int values = 0;
    std::function<void(char **)> set;
  };
  std::string usage_;
  std::map<std::string, Option> options_;
};

} // namespace bench
} // namespace yawdepth
