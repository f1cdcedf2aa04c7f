#pragma once
/*!
  \file detector.h
  \brief Pattern features in images: chessboard corners (OpenCV, sub-pixel) and AprilTags (ViSP),
  with stable ids (see pattern.h) and reasons for failures.
*/
#include <memory>
#include <string>
#include <vector>
#include <opencv2/core.hpp>
#include <yawdepth/camera/camera_model.h>
#include <yawdepth/core/types.h>
#include <yawdepth/features/pattern.h>

namespace yawdepth {

/*! \brief Detection result of one image. */
struct FrameDetection {
  long frame = 0;             //!< frame number given to detect()
  bool found = false;         //!< false: no usable pattern; `reason` says why
  std::string reason;         //!< e.g. "chessboard 5x4 not found", "image unreadable"
  std::vector<FeatureObservation> features; //!< the detected features (empty when not found)
  /*! Features kept but less sure, one line each: e.g. "corner 17: sub-pixel refinement failed,
      the detector's estimate kept", or AprilTag ids of the board seen twice and dropped. */
  std::vector<std::string> warnings;
};

/*!
  \brief A picture to check a detection by eye: the image in colour, each feature as a cross with
  its id (chessboard: corner 0 in red, the board's X direction along the first row in green), the
  warnings' features circled in orange, and the reason on top when the pattern was not found.
  \param image The image that was given to detect() (grayscale or colour). \param detection Its result.
*/
cv::Mat drawDetection(const cv::Mat &image, const FrameDetection &detection);

/*!
  \brief Sub-pixel refinement of chessboard corners (each corner on its own: no homography or
  planarity constraint across corners).

  All but `None` start from OpenCV's cv::findChessboardCornersSB estimate.
*/
enum class CornerRefinement {
  None,     //!< the detector's own estimate (findChessboardCornersSB with CALIB_CB_ACCURACY)
  OpenCV,   //!< cv::cornerSubPix, half-window 0.2 x the corner spacing (2..5 px), tight termination
  Saddle,   //!< iterated saddle-point fit: Gaussian-weighted quadratic surface, window chosen as for Gradient
  /*! iterated gradient orthogonality, Gaussian window on the pixel grid (no resampling), the
      window chosen per corner: the largest (sigma 1 px up to a quarter of the spacing, at most
      10 px) over which the image stays point-symmetric about the corner */
  Gradient
};

/*! \brief Options of the detector. */
struct DetectorOptions {
  bool subpixel = true;         //!< chessboard: sub-pixel refinement of the corners
  CornerRefinement refinement = CornerRefinement::Gradient; //!< chessboard: method when `subpixel`
  /*! half-size of the refinement window (px), the same for every corner; 0 = chosen per corner
      (Gradient) or from the corner spacing (the others) */
  int subpixel_window = 0;
  double apriltag_decimate = 1; //!< ViSP quad decimation (1 = full resolution, most accurate)
  int threads = 1;              //!< number of threads of the detection
};

/*!
  \brief Detects a pattern in grayscale images and returns features with stable ids.

  Stateful only to keep chessboard ids consistent between frames when the board is symmetric
  (COLS + ROWS even, or square), where one image cannot tell the board's own orientation.

  Chessboard: cv::findChessboardCorners (fast), else cv::findChessboardCornersSB (plain, then
  exhaustive) locate the corners; cv::cornerSubPix then the chosen refinement (default
  CornerRefinement::Gradient) measure each corner on its own. Ids: of the grid labellings that keep
  the board's handedness (board X then Y clockwise in the image, the board seen from the front),
  those whose square colours match the board (square (i, j) black iff i + j even) are kept; one
  remains when COLS + ROWS is odd and COLS != ROWS. Otherwise (symmetric board) the labelling
  nearest to the previous successful frame's pixels is taken, or, with no history, the one with id
  0 nearest the image's top-left corner.
  The Gradient window: a window large enough to average noise reaches, at the board's outer
  corners, past the narrow outer squares many printed boards have, or into a highlight, an
  occluder or the image border; there the X-junction's point symmetry ends and the corner is
  dragged by pixels. Each corner therefore climbs a ladder of windows (sigma 1 px, x sqrt 2, up to
  a quarter of the spacing) and keeps the largest whose asymmetry (RMS of I(x) - I(2q - x) over its
  contrast) stays within 1.3x (+0.01) of the least seen on the way.
  Measured by `bench_corners` (homography RMS of the undistorted corners, median per image, px;
  yawdepth / cornerSubPix 11x11 / findChessboardCornersSB + ACCURACY):
  real photographs: franka-eye-in-hand 0.144 / 0.149 / 0.192, OpenCV's left*.jpg 0.127 / 0.142 /
  0.183, right*.jpg 0.139 / 0.159 / 0.205; photo-like renders (JPEG, gamma, vignetting, Bayer,
  defocus, wide lens): error against the truth 0.035 / 0.056 / 0.084.

  AprilTag: vpDetectorAprilTag (quad decimation `apriltag_decimate`, edge refinement on); features
  per pattern.h; a tag id seen twice in one image is dropped (ambiguous).
  Failure reasons (FrameDetection::reason): "empty image", "unsupported image type ...",
  "chessboard CxR not found", "chessboard CxR: cannot tell the board's orientation (square
  colours)", "... too little contrast ...", "no AprilTag of family F found", "OpenCV error: ...".
*/
class PatternDetector {
public:
  /*! \brief Throws yawdepth::Error for an invalid pattern or options, or an AprilTag family that
      ViSP's detector does not have. */
  PatternDetector(const PatternSpec &pattern, const DetectorOptions &options = DetectorOptions());
  ~PatternDetector();
  /*! \brief Move constructor. */
  PatternDetector(PatternDetector &&) noexcept;
  /*! \brief Move assignment. */
  PatternDetector &operator=(PatternDetector &&) noexcept;

  /*!
    \brief The camera the images come from (optional). Used for the AprilTag centre feature: the
    intersection of the tag's diagonals is taken on undistorted corners and distorted back, which
    is the exact image of the tag centre; without a camera the diagonals are intersected in the
    (distorted) image. Chessboard corners do not use it.
  */
  void setCamera(const CameraModel &camera);

  /*! \brief Detect in an 8-bit grayscale (or BGR, converted) image. Never throws on bad images. */
  FrameDetection detect(const cv::Mat &image, long frame);

  /*! \brief Convert detections of a sequence into tracks (one per id, observations sorted by frame). */
  static std::vector<Track> toTracks(const std::vector<FrameDetection> &frames);

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/*!
  \brief Refine chessboard corners (X-junctions) in place, each on its own.
  \param gray 8-bit grayscale image.
  \param corners Initial estimates (px, pixel centres at integer coordinates), refined in place;
  a corner whose refinement fails or moves by more than a quarter of the spacing keeps its input.
  \param spacing_px Smallest distance between neighbouring corners (px): sets the window.
  \param method The refinement method.
  \param window Half-size of the window (px); 0 = from `spacing_px`.
  \param refined If not null, receives for each corner whether its refinement succeeded (false:
  the input was kept).
*/
void refineChessboardCorners(const cv::Mat &gray, std::vector<cv::Point2d> &corners, double spacing_px,
                             CornerRefinement method, int window = 0, std::vector<bool> *refined = nullptr);

/*!
  \brief Refine the centres of a planar grid of dark round dots on a light ground (ViSP's
  calibration grid, OpenCV's symmetric circle grid), given roughly (e.g. by cv::findCirclesGrid).
  Each dot's outline is found on 64 rays from its rough centre (the gradient's peak along the ray,
  to a quarter pixel and a parabola; rays whose edge strays from the median radius, e.g. on marks
  printed inside the dot, are dropped) and fitted by an ellipse C. The dot's centre of darkness is
  then the centroid of w = (ground - I) / (ground - dot), clipped to 0..1, over the ellipse and a
  ring around it, with w = 1 inside 0.8 of the outline (marks in the dot do not count): blur moves
  no first moment, so this is the imaged ellipse's centre to a few thousandths of a pixel. Under
  perspective the image of a circle's centre is not that: it is the pole of the image of the
  plane's line at infinity with respect to the ellipse, \f$ c \propto C^{-1} H^{-T} (0, 0, 1)^T \f$
  (H the grid's board-to-image homography), so the pole's offset from the ellipse's centre is
  added. Distortion is not modelled (dots are small against it). A dot whose outline or centroid
  cannot be measured keeps its input.
  Measured (bench_corners): on rendered 6x6 grids under perspective (blur 0.8 px, noise 2) the
  error against the truth is 0.005 px against cv::findCirclesGrid's 0.009 px; on ViSP's real
  grid36 photos the homography RMS is 0.203 px against 0.220 px.
  \param gray 8-bit grayscale image.
  \param centres Row-major over the grid (`cols` per row), refined in place.
  \param cols, rows The grid's size.
  \return The number of dots refined.
*/
int refineDotGridCentres(const cv::Mat &gray, std::vector<cv::Point2d> &centres, int cols, int rows);

/*! \brief Read an image file as 8-bit grayscale; throws yawdepth::Error (unreadable, truncated, empty). */
cv::Mat readGrayImage(const std::string &path);
/*! \brief Same, and throws yawdepth::Error ("PATH: image is WxH but the camera is WxH") when the
    camera has an image size and the image is of another. */
cv::Mat readGrayImage(const std::string &path, const CameraModel &camera);

} // namespace yawdepth
