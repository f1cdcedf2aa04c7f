#pragma once
/*!
  \file camera_file.h
  \brief Read camera files: ViSP camera XML (vpXmlParserCamera), OpenCV YAML/XML (cv::FileStorage),
  ROS camera_info YAML and Kalibr camchain YAML (cv::FileStorage's YAML parser, read node by node);
  write OpenCV and ROS YAML.
*/
#include <string>
#include <yawdepth/camera/camera_model.h>

namespace yawdepth {

/*!
  \brief Load a camera file.

  - ViSP XML (root element `<root>` with `<camera>` entries, as vpXmlParserCamera writes them):
    `camera_name` picks the camera; it may be empty when the file holds exactly one camera. The
    model with distortion (kud) is used when present, else the one without.
  - OpenCV YAML or XML (cv::FileStorage): `camera_matrix` (3x3), `distortion_coefficients`
    (0, 4, 5 or 8 values), `image_width`, `image_height`; an optional `distortion_model` word:
    `plumb_bob` or `rational_polynomial` (the Brown model, as without the key) or `equidistant`
    (also `fisheye`: cv::fisheye's Kannala-Brandt model, 4 coefficients k1 k2 k3 k4).
  - ROS camera_info YAML, as ROS camera_calibration and camera_info_manager write it (told from
    OpenCV's YAML by its `camera_matrix: {rows: 3, cols: 3, data: [...]}` without the
    `!!opencv-matrix` tag): `image_width`, `image_height`, `camera_matrix`, `distortion_model`
    (`plumb_bob`, `rational_polynomial`, `equidistant`; absent: plumb_bob, as ROS assumes),
    `distortion_coefficients` (`{rows: 1, cols: N, data: [...]}`); `rectification_matrix` and
    `projection_matrix` are checked (3x3, 3x4) but not used: observed pixels are raw image pixels,
    undistorted with camera_matrix and the distortion. A `camera_name` given must equal the file's.
  - Kalibr camchain YAML (`cam0:`, `cam1:`, ... each with `camera_model: pinhole`, `intrinsics:
    [fu, fv, pu, pv]`, `distortion_model` `radtan` (k1 k2 r1 r2 = OpenCV's k1 k2 p1 p2),
    `equidistant` or `none`, `distortion_coeffs`, `resolution: [w, h]`; other keys ignored):
    `camera_name` picks the camera, cam0 when empty.

  \throws yawdepth::Error with a one-line reason (missing file, unknown camera name, missing key,
  non-finite or non-positive focal length, wrong number of coefficients, ...).
*/
CameraModel loadCameraFile(const std::string &path, const std::string &camera_name = "");

/*!
  \brief Throws yawdepth::Error ("WHAT: implausible camera: why") for a camera that cannot be a real
  one: focal lengths outside 1e-3..1e6 px or with an aspect ratio beyond 10, an image side over
  65535 px, a principal point more than half an image outside the image, or (image size known) a
  distortion that is not invertible over the whole image (not monotonic along a ray from the
  centre, Newton's inverse failing) or that maps it to a field more than 10x wider or narrower than
  the pinhole would. For a Kannala-Brandt (fisheye) camera, \f$ \theta_d(\theta) \f$ must increase
  from the centre to the image's farthest corner, or to 90 degrees when the image reaches beyond;
  pixels whose rays are at 90 degrees or more (a field over 180 degrees, corners outside the
  image circle) are not used and not checked, and the field rule applies to rays within 80
  degrees. loadCameraFile() applies it to every file it reads.
  \param camera The camera. \param what What to name in the message (a file, a model).
*/
void checkCameraPlausible(const CameraModel &camera, const std::string &what);

/*!
  \brief An OpenCV YAML camera file's text (the format loadCameraFile() reads). A Kannala-Brandt
  camera gets `distortion_model: equidistant` and its 4 coefficients. \param camera The camera.
*/
std::string cameraYamlText(const CameraModel &camera);
/*!
  \brief Write cameraYamlText() to `path` atomically (a temporary file beside it, renamed over it).
  \param path The file. \param camera The camera.
*/
void saveCameraYaml(const std::string &path, const CameraModel &camera);

/*!
  \brief A ROS camera_info YAML file's text, laid out as ROS camera_calibration's ost.yaml (the
  file camera_info_manager loads): image_width, image_height, camera_name, camera_matrix,
  distortion_model, distortion_coefficients, rectification_matrix (identity), projection_matrix
  ([K | 0]). Brown with k4..k6 becomes `rational_polynomial` (8 coefficients), other Brown, ViSP
  (k1 = kud) and no distortion `plumb_bob` (5), Kannala-Brandt `equidistant` (4). Numbers are
  written in their shortest exact form. An unknown image size is written as 0.
  \param camera The camera. \param camera_name Its name (empty: "camera").
*/
std::string rosCameraInfoYamlText(const CameraModel &camera, const std::string &camera_name);
/*!
  \brief Write rosCameraInfoYamlText() to `path` atomically (a temporary file beside it, renamed over it).
  \param path The file. \param camera The camera. \param camera_name Its name (empty: "camera").
*/
void saveRosCameraInfoYaml(const std::string &path, const CameraModel &camera, const std::string &camera_name);

} // namespace yawdepth
