/*!
  \file renderer.cpp
  \brief renderBoard(): exact back-projection of every pixel through the camera's distortion onto the
  board plane, anti-aliasing by supersampling the pixel's footprint where it straddles an edge,
  then what makes it a photograph (light, defocus, mosaic, noise, response curve, JPEG), each optional.
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
#include <opencv2/imgcodecs.hpp>
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
    const double s = board.pattern.square, o = board.outer_square > 0 ? board.outer_square : s;
    g.xs.push_back(-o);
    g.ys.push_back(-o);
    for (int k = 0; k < board.pattern.cols; ++k)
      g.xs.push_back(k * s);
    for (int k = 0; k < board.pattern.rows; ++k)
      g.ys.push_back(k * s);
    g.xs.push_back((board.pattern.cols - 1) * s + o);
    g.ys.push_back((board.pattern.rows - 1) * s + o);
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
  k.insert(k.end(), c.kannalaBrandtCoefficients().begin(), c.kannalaBrandtCoefficients().end());
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

/*! \brief splitmix64: a well-mixed 64-bit hash of a lattice cell and the seed. */
std::uint64_t mix(std::uint64_t z) {
  z += 0x9e3779b97f4a7c15ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

/*!
  \brief The wall's texture at board-plane point (x, y) (m): value noise (uniform lattice values
  blended by the quintic fade, so the texture is twice differentiable) of three octaves, cells of
  `texel`, `texel` / 2 and `texel` / 4 with weights 1, 1/2, 1/4, contrast-stretched to 0..1.
*/
double wallReflectance(double x, double y, double texel, std::uint64_t seed) {
  double sum = 0, weight = 1, cell = texel;
  for (int octave = 0; octave < 3; ++octave, weight *= 0.5, cell *= 0.5) {
    const double X = x / cell, Y = y / cell;
    if (!(std::abs(X) < 1e15 && std::abs(Y) < 1e15))
      return 0.5;
    const double fx = std::floor(X), fy = std::floor(Y);
    const auto ix = static_cast<std::int64_t>(fx), iy = static_cast<std::int64_t>(fy);
    auto lattice = [&](std::int64_t i, std::int64_t j) {
      const std::uint64_t h = mix(mix(mix(seed + static_cast<std::uint64_t>(octave)) + static_cast<std::uint64_t>(i)) +
                                  static_cast<std::uint64_t>(j));
      return static_cast<double>(h >> 11) * 0x1.0p-53;
    };
    auto fade = [](double t) { return t * t * t * (t * (6 * t - 15) + 10); };
    const double a = fade(X - fx), b = fade(Y - fy);
    const double v0 = lattice(ix, iy) + a * (lattice(ix + 1, iy) - lattice(ix, iy));
    const double v1 = lattice(ix, iy + 1) + a * (lattice(ix + 1, iy + 1) - lattice(ix, iy + 1));
    sum += weight * (v0 + b * (v1 - v0));
  }
  return std::clamp(0.5 + 2.0 * (sum / 1.75 - 0.5), 0.0, 1.0);
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
  if (!(o.light_gradient >= 0 && o.light_gradient <= 1) || !std::isfinite(o.light_angle))
    throw Error("render: the light gradient must be 0 to 1 (and its angle finite)");
  if (!(o.vignetting >= 0 && o.vignetting <= 1))
    throw Error("render: vignetting must be 0 to 1");
  if (!(o.defocus_px >= 0 && o.defocus_px <= 1000))
    throw Error("render: defocus must be 0 to 1000 px");
  if (o.defocus_px > 0 && !(o.focus_distance > 0 && std::isfinite(o.focus_distance)))
    throw Error("render: defocus needs a focus distance > 0 (m)");
  if (!(o.shot_noise >= 0) || !std::isfinite(o.shot_noise))
    throw Error("render: shot noise must be finite and >= 0");
  if (!(o.gamma >= 0.1 && o.gamma <= 10))
    throw Error("render: gamma must be 0.1 to 10");
  if (o.jpeg_quality < 0 || o.jpeg_quality > 100)
    throw Error("render: JPEG quality must be 0 (none) to 100");
  if (!(o.wall_texel >= 0 && o.wall_texel <= 1000))
    throw Error("render: the wall texel must be 0 (no wall) to 1000 m");
}

RenderOptions photoLikeRenderOptions(double focus_distance) {
  RenderOptions o;
  o.blur_sigma_px = 0.6;
  o.noise_sigma = 1.5;
  o.light_gradient = 0.3;
  o.vignetting = 0.35;
  o.defocus_px = 1.5;
  o.focus_distance = focus_distance;
  o.bayer = true;
  o.shot_noise = 0.15;
  o.gamma = 2.2;
  o.jpeg_quality = 85;
  return o;
}

namespace {

/*! \brief Blur sigma (px) of each pixel: optical blur and defocus, added in quadrature. */
cv::Mat blurSigmas(const cv::Mat &depth, const RenderOptions &o) {
  cv::Mat sig(depth.size(), CV_32F, cv::Scalar(o.blur_sigma_px));
  if (!(o.defocus_px > 0))
    return sig;
  // The background (no board) gets the optical blur alone.
  for (int v = 0; v < depth.rows; ++v) {
    const float *z = depth.ptr<float>(v);
    float *s = sig.ptr<float>(v);
    for (int u = 0; u < depth.cols; ++u) {
      const double d = z[u] > 0 ? o.defocus_px * std::abs(o.focus_distance / z[u] - 1.0) : 0.0;
      s[u] = static_cast<float>(std::sqrt(o.blur_sigma_px * o.blur_sigma_px + d * d));
    }
  }
  return sig;
}

/*! \brief Spatially varying Gaussian blur: the image blurred at a ladder of sigmas, each pixel
    interpolated linearly between the two levels around its own sigma. */
cv::Mat varyingBlur(const cv::Mat &img, const cv::Mat &sigmas) {
  double smin = 0, smax = 0;
  cv::minMaxLoc(sigmas, &smin, &smax);
  if (!(smax > 0))
    return img;
  if (smax - smin < 1e-6) {
    cv::Mat out;
    cv::GaussianBlur(img, out, cv::Size(0, 0), smax, smax, cv::BORDER_REPLICATE);
    return out;
  }
  // levels 0, step, 2 step, ... up to smax (step 0.25 px, at most 64 levels)
  const double step = std::max(0.25, smax / 64);
  const int n = static_cast<int>(std::ceil(smax / step)) + 1;
  std::vector<cv::Mat> levels(static_cast<std::size_t>(n));
  for (int k = 0; k < n; ++k) {
    const double s = k * step;
    if (s < smin - step || s > smax + step)
      continue;
    if (s <= 0)
      levels[static_cast<std::size_t>(k)] = img;
    else
      cv::GaussianBlur(img, levels[static_cast<std::size_t>(k)], cv::Size(0, 0), s, s, cv::BORDER_REPLICATE);
  }
  cv::Mat out(img.size(), CV_32F);
  for (int v = 0; v < img.rows; ++v) {
    const float *sg = sigmas.ptr<float>(v);
    float *o = out.ptr<float>(v);
    for (int u = 0; u < img.cols; ++u) {
      const double t = sg[u] / step;
      const int k0 = std::min(static_cast<int>(t), n - 1), k1 = std::min(k0 + 1, n - 1);
      const double a = t - k0;
      const float f0 = levels[static_cast<std::size_t>(k0)].ptr<float>(v)[u];
      const float f1 = levels[static_cast<std::size_t>(k1)].empty() ? f0 : levels[static_cast<std::size_t>(k1)].ptr<float>(v)[u];
      o[u] = static_cast<float>((1 - a) * f0 + a * f1);
    }
  }
  return out;
}

/*! \brief From the ideal radiance image (gray levels as linear light) to the 8-bit picture:
    light, blur, mosaic, noise, demosaicing, response curve, rounding, JPEG (RenderOptions). */
cv::Mat finishImage(cv::Mat img, const cv::Mat &depth, const RenderOptions &o) {
  const int W = img.cols, H = img.rows;
  if (o.light_gradient > 0 || o.vignetting > 0) {
    const double cu = 0.5 * (W - 1), cv_ = 0.5 * (H - 1), r2max = cu * cu + cv_ * cv_;
    const double ca = std::cos(o.light_angle), sa = std::sin(o.light_angle);
    const double extent = std::abs(ca) * W + std::abs(sa) * H; // the image's length along the gradient
    for (int v = 0; v < H; ++v) {
      float *row = img.ptr<float>(v);
      for (int u = 0; u < W; ++u) {
        const double du = u - cu, dv = v - cv_;
        const double along = (du * ca + dv * sa) / extent; // -1/2 .. 1/2 across the image
        const double light = (1 + o.light_gradient * along) * (1 - o.vignetting * (du * du + dv * dv) / r2max);
        row[u] = static_cast<float>(row[u] * light);
      }
    }
  }
  img = varyingBlur(img, blurSigmas(depth, o));
  std::mt19937_64 rng(o.seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  // Bayer RGGB: raw level of each pixel = its channel's sensitivity x the light; white balance
  // after demosaicing divides it back, so the noise differs per channel as in a camera.
  const double sens[3] = {0.55, 1.0, 0.75}; // R, G, B
  auto channel = [](int u, int v) { return (v % 2 == 0) ? (u % 2 == 0 ? 0 : 1) : (u % 2 == 0 ? 1 : 2); };
  if (o.noise_sigma > 0 || o.shot_noise > 0 || o.bayer) {
    for (int v = 0; v < H; ++v) {
      float *row = img.ptr<float>(v);
      for (int u = 0; u < W; ++u) {
        const double s = o.bayer ? sens[channel(u, v)] : 1.0;
        const double raw = row[u] * s;
        const double sd = std::sqrt(o.noise_sigma * o.noise_sigma + o.shot_noise * std::max(raw, 0.0));
        row[u] = static_cast<float>(sd > 0 ? raw + sd * gauss(rng) : raw);
      }
    }
  }
  if (o.bayer) {
    cv::Mat raw8;
    img.convertTo(raw8, CV_8U); // the sensor's 8-bit raw
    cv::Mat bgr;
    // OpenCV names Bayer patterns by the second row's first two pixels: RGGB is "BayerBG".
    cv::demosaicing(raw8, bgr, cv::COLOR_BayerBG2BGR);
    std::vector<cv::Mat> ch;
    cv::split(bgr, ch);
    cv::Mat b, g, r;
    ch[0].convertTo(b, CV_32F, 1.0 / sens[2]);
    ch[1].convertTo(g, CV_32F, 1.0 / sens[1]);
    ch[2].convertTo(r, CV_32F, 1.0 / sens[0]);
    img = 0.299 * r + 0.587 * g + 0.114 * b;
  }
  if (o.gamma != 1) {
    const double inv = 1.0 / o.gamma;
    for (int v = 0; v < H; ++v) {
      float *row = img.ptr<float>(v);
      for (int u = 0; u < W; ++u)
        row[u] = static_cast<float>(255.0 * std::pow(std::clamp(row[u] / 255.0, 0.0, 1.0), inv));
    }
  }
  cv::Mat out;
  img.convertTo(out, CV_8U); // rounds and saturates to 0..255
  if (o.jpeg_quality > 0) {
    std::vector<uchar> buf;
    cv::imencode(".jpg", out, buf, {cv::IMWRITE_JPEG_QUALITY, o.jpeg_quality});
    out = cv::imdecode(buf, cv::IMREAD_GRAYSCALE);
    if (out.empty())
      throw Error("render: JPEG round trip failed");
  }
  return out;
}

} // namespace

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
  const double texel = options.wall_texel;
  const bool wall = texel > 0;
  // The gray level at board-plane point (x, y): the board, else the wall or the background.
  auto gray = [&](double x, double y) {
    double rho = board.reflectance(x, y);
    if (rho < 0 && wall)
      rho = wallReflectance(x, y, texel, options.wall_seed);
    return rho < 0 ? bg : black + (white - black) * rho;
  };

  cv::Mat img(H, W, CV_32F);
  cv::Mat depth(H, W, CV_32F, cv::Scalar(0)); // camera Z of the board at each pixel; 0 = background
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
        depth.ptr<float>(v)[u] = static_cast<float>(s);
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
        // One sample where the reflectance is constant over the footprint: no edge crossed, and
        // not on the wall unless the footprint is small against its finest blobs.
        const bool on_wall = wall && board.reflectance(P.x(), P.y()) < 0;
        if (grid.uniform(P.x() - hx, P.x() + hx, P.y() - hy, P.y() + hy) &&
            (!on_wall || std::max(hx, hy) < texel / 16)) {
          row[u] = static_cast<float>(gray(P.x(), P.y()));
          continue;
        }
        double acc = 0;
        for (const Eigen::Vector2d &d : samples) {
          const Eigen::Vector2d Q = P + A * d;
          acc += gray(Q.x(), Q.y());
        }
        row[u] = static_cast<float>(acc / n);
      }
    }
  });

  return finishImage(img, depth, options);
}

} // namespace yawdepth
