#pragma once
/*!
  \file renderer.h
  \brief Renders what the yawing camera sees of a planar board: the camera's distortion,
  anti-aliasing (exact area coverage by supersampling of each pixel's footprint), optional optical
  blur and sensor noise. Used by `yawdepth simulate --pattern` and by the tests.

  Per pixel (centre at integer (u, v), footprint [u - 1/2, u + 1/2] x [v - 1/2, v + 1/2]): the
  exact back-projection (CameraModel::undistort, Newton to convergence) gives the ray, intersected
  with the board plane; the footprint is mapped onto the board by the local affine Jacobian
  (undistortion Jacobian times the plane mapping). When the footprint's bounding box on the board
  crosses a line where the reflectance may change (square or bitmap-cell edges, the board outline)
  the pixel averages k x k samples of the footprint (a Hammersley set: stratified in both axes, so
  an axis-aligned edge is resolved to 1/k^2 of a pixel, not 1/k); else one sample. Pixels whose ray
  misses the board, hits it behind the camera, or cannot be undistorted get `background`; with a
  wall (RenderOptions::wall_texel) the board's plane beyond the outline is textured instead, and its
  pixels average the k x k samples wherever the footprint is wider than a sixteenth of the texel. Then the
  optional blur (cv::GaussianBlur, the discrete Gaussian on the pixel grid, replicated border) and
  noise (std::mt19937_64 seeded by `seed`, row-major order), rounding and clamping to 0..255.
  The undistortion of every pixel is cached for the last four cameras (thread-safe): the first
  frame of a camera pays for it (about 0.25 s of one core at 640x480, spread over cv::parallel_for_),
  later frames cost about 10-60 ms each at 640x480 (blur and noise included).
*/
#include <Eigen/Geometry>
#include <cstdint>
#include <opencv2/core.hpp>
#include <yawdepth/camera/camera_model.h>
#include <yawdepth/features/pattern.h>
#include <yawdepth/geometry/rig.h>

namespace yawdepth {

/*! \brief Options of renderBoard(). */
struct RenderOptions {
  int supersampling = 8;       //!< k x k samples per pixel where the pixel straddles an edge (1..64)
  double blur_sigma_px = 0.0;  //!< Gaussian optical blur (px); 0 = none
  double noise_sigma = 0.0;    //!< Gaussian sensor noise (gray levels); 0 = none
  double black = 25;           //!< gray level of the board's black parts
  double white = 230;          //!< gray level of the board's white parts
  double background = 110;     //!< gray level around the board
  std::uint64_t seed = 1;      //!< noise seed
  /*! The board hangs on a wall: with `wall_texel` > 0 the board's plane beyond its outline carries a
      smooth random texture instead of `background` (value noise of three octaves, blobs about
      `wall_texel` m across down to a quarter of it, seeded by `wall_seed`, gray levels between
      `black` and `white`), which natural-feature trackers follow. 0 = no wall. */
  double wall_texel = 0;
  std::uint64_t wall_seed = 1; //!< the wall's texture (one per scene, unlike `seed`)

  /*! \name What makes a render look like a photograph (all off by default)
      Applied in this order, the gray levels above taken as linear light (0..255):
      light gradient and vignetting, defocus that grows with the distance to the focused depth (and
      `blur_sigma_px`), the Bayer mosaic (RGGB, per-channel sensitivity 0.55 / 1 / 0.75), noise
      (Gaussian `noise_sigma` plus shot noise of variance `shot_noise` times the raw level),
      bilinear demosaicing and white balance, the response curve (`gamma`), 8-bit rounding and JPEG. */
  //!@{
  double light_gradient = 0;   //!< relative change of the light across the image, along `light_angle` (0..1)
  double light_angle = 0.5;    //!< direction of the light gradient in the image (rad from +u)
  double vignetting = 0;       //!< relative fall-off of the light at the image corners, quadratic in the radius (0..1)
  double defocus_px = 0;       //!< defocus blur sigma (px) = defocus_px x |focus_distance / Z - 1|; 0 = none
  double focus_distance = 0;   //!< depth in focus (camera Z, m); needed when `defocus_px` > 0
  bool bayer = false;          //!< Bayer mosaic (RGGB) and OpenCV's bilinear demosaicing
  double shot_noise = 0;       //!< shot noise: variance (gray levels^2) per gray level of raw signal
  double gamma = 1;            //!< response curve: out = 255 (in / 255)^(1 / gamma); 1 = linear
  int jpeg_quality = 0;        //!< JPEG round trip at this quality (1..100); 0 = none
  //!@}
};

/*! \brief Options that make renders look like photographs from a consumer camera: light gradient
    0.3, vignetting 0.35, defocus 1.5 px focused at `focus_distance`, Bayer, noise 1.5 + shot noise
    0.15, gamma 2.2, JPEG 85, optical blur 0.6 px. \param focus_distance Depth in focus (m). */
RenderOptions photoLikeRenderOptions(double focus_distance);

/*!
  \brief Throws yawdepth::Error when renderBoard() would refuse `camera` or `options` (no image size,
  an image over 20000 px a side, supersampling outside 1..64, blur or defocus outside 0..1000 px,
  negative or non-finite noise or gray levels, light gradient or vignetting outside 0..1, gamma
  outside 0.1..10, JPEG quality outside 0..100, defocus without a focus distance, a wall texel
  negative, non-finite or over 1000 m): for a check
  before any file is written.
  \param camera The camera. \param options The options.
*/
void checkRenderOptions(const CameraModel &camera, const RenderOptions &options);

/*!
  \brief Render one grayscale view (8-bit, camera's image size) of a board.
  \param camera Camera model (with an image size).
  \param rig Yaw rig.
  \param board The board.
  \param wMb Pose of the board frame in the world (see pattern.h for the board frame).
  \param options Rendering options.
  \param sample The motion-log row: the vision frame's pose and the camera yaw.
  The camera must have an image size; throws yawdepth::Error for it, bad options or non-finite poses.
  The exact pixel of a board feature is `camera.project()` of its normalised camera-frame point.
*/
cv::Mat renderBoard(const CameraModel &camera, const YawRig &rig, const MotionSample &sample,
                    const BoardLayout &board, const Eigen::Isometry3d &wMb, const RenderOptions &options = RenderOptions());

} // namespace yawdepth
