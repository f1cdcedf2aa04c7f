/*!
  \file renderer.cpp
  \brief renderBoard(): exact back-projection of every pixel through the camera's distortion onto the
  board plane, anti-aliasing by supersampling the pixel's footprint where it straddles an edge,
  then optional Gaussian blur and noise.
*/
#include <yawdepth/render/renderer.h>

#include <algorithm>
#include <cmath>
#include <list>
#include <memory>
#include <mutex>
#include <random>
#include <vector>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>
#include <yawdepth/error.h>

namespace yawdepth {

namespace {

/*!
  \brief Every line of the board (in the board frame) across which the reflectance may change:
  chessboard square edges, AprilTag bitmap cell edges and the board's outline. Between two
  consecutive X lines and two consecutive Y lines the reflectance is constant.
*/
struct EdgeGrid {
  std::vector<double> xs, ys;

  /*! \brief True when the open box (x0, x1) x (y0, y1) contains no edge line. */
  bool uniform(double x0, double x1, double y0, double y1) const {
    auto crosses = [](const std::vector<double> &v, double a, double b) {
      auto it = std::upper_bound(v.begin(), v.end(), a);
      return it != v.end() && *it < b;
    };
    return !crosses(xs, x0, x1) && !crosses(ys, y0, y1);
  }
};

EdgeGrid makeEdgeGrid(const BoardLayout &board) {
  EdgeGrid g;
  const Eigen::Vector4d e = board.extent();
  g.xs = {e[0], e[2]};
  g.ys = {e[1], e[3]};
  if (board.pattern.kind == PatternSpec::Kind::Chessboard) {
    const double s = board.pattern.square;
    for (int k = -1; k <= board.pattern.cols; ++k)
      g.xs.push_back(k * s);
    for (int k = -1; k <= board.pattern.rows; ++k)
      g.ys.push_back(k * s);
  } else {
    const AprilTagFamilyInfo f = aprilTagFamilyInfo(board.pattern.family);
    const double s = board.pattern.tag_size, pitch = s + board.gap, cell = s / f.width_at_border;
    const double off = 0.5 * (f.total_width - f.width_at_border);
    for (int c = 0; c < board.tags_x; ++c)
      for (int k = 0; k <= f.total_width; ++k)
        g.xs.push_back(c * pitch + (k - off) * cell);
    for (int r = 0; r < board.tags_y; ++r)
      for (int k = 0; k <= f.total_width; ++k)
        g.ys.push_back(r * pitch + (k - off) * cell);
  }
  std::sort(g.xs.begin(), g.xs.end());
  std::sort(g.ys.begin(), g.ys.end());
  return g;
}

/*!
  \brief Per-pixel undistortion of a camera: CameraModel::undistort() of every pixel centre, with its
  Jacobian. Computing it dominates a frame, and a sequence renders many frames with one camera, so
  the last few maps are cached (keyed by every camera parameter).
*/
struct UndistortMap {
  std::vector<double> key;
  int width = 0, height = 0;
  std::vector<Eigen::Vector2d> m;      //!< normalised point of each pixel
  std::vector<Eigen::Matrix2d> J;      //!< d(x, y)/d(u, v)
  std::vector<unsigned char> valid;    //!< undistortion converged
};

std::vector<double> cameraKey(const CameraModel &c) {
  std::vector<double> k = {static_cast<double>(c.distortion()), c.kx(), c.ky(), c.u0(), c.v0(),
                           static_cast<double>(c.width()), static_cast<double>(c.height())};
  k.insert(k.end(), c.brownCoefficients().begin(), c.brownCoefficients().end());
  return k;
}

std::shared_ptr<const UndistortMap> undistortMap(const CameraModel &camera) {
  static std::mutex mutex;
  static std::list<std::shared_ptr<const UndistortMap>> cache; // most recent first
  const std::vector<double> key = cameraKey(camera);
  {
    std::lock_guard<std::mutex> lock(mutex);
    for (auto it = cache.begin(); it != cache.end(); ++it)
      if ((*it)->key == key) {
        auto hit = *it;
        cache.erase(it);
        cache.push_front(hit);
        return hit;
      }
  }
  auto map = std::make_shared<UndistortMap>();
  map->key = key;
  map->width = static_cast<int>(camera.width());
  map->height = static_cast<int>(camera.height());
  const std::size_t n = static_cast<std::size_t>(map->width) * map->height;
  map->m.resize(n);
  map->J.resize(n);
  map->valid.assign(n, 0);
  cv::parallel_for_(cv::Range(0, map->height), [&](const cv::Range &range) {
    for (int v = range.start; v < range.end; ++v)
      for (int u = 0; u < map->width; ++u) {
        const std::size_t i = static_cast<std::size_t>(v) * map->width + u;
        map->valid[i] = camera.undistort(Eigen::Vector2d(u, v), map->m[i], &map->J[i]) ? 1 : 0;
      }
  });
  std::lock_guard<std::mutex> lock(mutex);
  cache.push_front(map);
  while (cache.size() > 4)
    cache.pop_back();
  return map;
}

/*! \brief Radical inverse in base 2 (van der Corput). */
double radicalInverse(unsigned i) {
  double f = 0.5, r = 0;
  while (i) {
    if (i & 1u)
      r += f;
    i >>= 1;
    f *= 0.5;
  }
  return r;
}

} // namespace

void checkRenderOptions(const CameraModel &camera, const RenderOptions &o) {
  if (camera.width() == 0 || camera.height() == 0)
    throw Error("render: the camera has no image size (width and height must be > 0)");
  if (camera.width() > 20000 || camera.height() > 20000)
    throw Error("render: image size " + std::to_string(camera.width()) + "x" + std::to_string(camera.height()) +
                " is too large (at most 20000x20000)");
  if (o.supersampling < 1 || o.supersampling > 64)
    throw Error("render: supersampling must be 1..64 (samples per pixel side)");
  // A blur wider than the image is a flat gray picture (and OpenCV's kernel size overflows).
  if (!std::isfinite(o.blur_sigma_px) || o.blur_sigma_px < 0 || o.blur_sigma_px > 1000)
    throw Error("render: blur sigma must be 0 to 1000 px");
  if (!std::isfinite(o.noise_sigma) || o.noise_sigma < 0)
    throw Error("render: noise sigma must be finite and >= 0");
  if (!std::isfinite(o.black) || !std::isfinite(o.white) || !std::isfinite(o.background))
    throw Error("render: gray levels must be finite");
}

cv::Mat renderBoard(const CameraModel &camera, const YawRig &rig, const MotionSample &sample,
                    const BoardLayout &board, const Eigen::Isometry3d &wMb, const RenderOptions &options) {
  checkRenderOptions(camera, options);
  const int W = static_cast<int>(camera.width()), H = static_cast<int>(camera.height());

  const Eigen::Isometry3d bMc = wMb.inverse() * toIsometry(wMc(rig, sample));
  const Eigen::Matrix3d bRc = bMc.linear();
  const Eigen::Vector3d o = bMc.translation();
  if (!bRc.allFinite() || !o.allFinite())
    throw Error("render: the board or camera pose is not finite");

  const EdgeGrid grid = makeEdgeGrid(board);
  const std::shared_ptr<const UndistortMap> umap = undistortMap(camera);
  const int k = options.supersampling;
  const int n = k * k;
  std::vector<Eigen::Vector2d> samples(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) // Hammersley set: stratified in both axes, low discrepancy for any edge direction
    samples[static_cast<std::size_t>(i)] =
        Eigen::Vector2d((i + 0.5) / n - 0.5, std::fmod(radicalInverse(static_cast<unsigned>(i)) + 0.5 / n, 1.0) - 0.5);

  const double black = options.black, white = options.white, bg = options.background;
  auto gray = [&](double rho) { return rho < 0 ? bg : black + (white - black) * rho; };

  cv::Mat img(H, W, CV_32F);
  cv::parallel_for_(cv::Range(0, H), [&](const cv::Range &range) {
    for (int v = range.start; v < range.end; ++v) {
      float *row = img.ptr<float>(v);
      for (int u = 0; u < W; ++u) {
        row[u] = static_cast<float>(bg);
        const std::size_t idx = static_cast<std::size_t>(v) * W + u;
        if (!umap->valid[idx])
          continue;
        const Eigen::Vector2d &m = umap->m[idx];
        const Eigen::Matrix2d &J = umap->J[idx]; // d(x, y) / d(u, v)
        const Eigen::Vector3d r = bRc * Eigen::Vector3d(m.x(), m.y(), 1.0);
        if (!(std::abs(r.z()) > 1e-12))
          continue;
        const double s = -o.z() / r.z(); // ray parameter (depth along the ray, camera Z units)
        if (!(s > 0) || !std::isfinite(s))
          continue;
        const Eigen::Vector2d P = (o + s * r).head<2>();
        // Board point as a function of (x, y): dP/dm_i = s (R_i - r R_iz / r_z), then the pixel
        // footprint's affine map A = dP/dm * dm/duv.
        Eigen::Matrix2d dPdm;
        for (int i = 0; i < 2; ++i) {
          const Eigen::Vector3d Ri = bRc.col(i);
          dPdm.col(i) = (s * (Ri - r * (Ri.z() / r.z()))).head<2>();
        }
        const Eigen::Matrix2d A = dPdm * J;
        // Bounding box of the footprint (the pixel square through A), a little enlarged.
        const double hx = 0.55 * (std::abs(A(0, 0)) + std::abs(A(0, 1)));
        const double hy = 0.55 * (std::abs(A(1, 0)) + std::abs(A(1, 1)));
        if (!std::isfinite(hx) || !std::isfinite(hy))
          continue;
        if (grid.uniform(P.x() - hx, P.x() + hx, P.y() - hy, P.y() + hy)) {
          row[u] = static_cast<float>(gray(board.reflectance(P.x(), P.y())));
          continue;
        }
        double acc = 0;
        for (const Eigen::Vector2d &d : samples) {
          const Eigen::Vector2d Q = P + A * d;
          acc += gray(board.reflectance(Q.x(), Q.y()));
        }
        row[u] = static_cast<float>(acc / n);
      }
    }
  });

  if (options.blur_sigma_px > 0)
    cv::GaussianBlur(img, img, cv::Size(0, 0), options.blur_sigma_px, options.blur_sigma_px, cv::BORDER_REPLICATE);
  if (options.noise_sigma > 0) {
    std::mt19937_64 rng(options.seed);
    std::normal_distribution<double> noise(0.0, options.noise_sigma);
    for (int v = 0; v < H; ++v) {
      float *row = img.ptr<float>(v);
      for (int u = 0; u < W; ++u)
        row[u] = static_cast<float>(row[u] + noise(rng));
    }
  }
  cv::Mat out;
  img.convertTo(out, CV_8U); // rounds and saturates to 0..255
  return out;
}

} // namespace yawdepth
