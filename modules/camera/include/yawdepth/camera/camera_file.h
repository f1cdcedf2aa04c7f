#pragma once
/*!
  \file camera_file.h
  \brief Read camera files: ViSP camera XML (vpXmlParserCamera) or OpenCV YAML/XML (cv::FileStorage).
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
    (0, 4, 5 or 8 values), `image_width`, `image_height`.

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
  the pinhole would. loadCameraFile() applies it to every file it reads.
  \param camera The camera. \param what What to name in the message (a file, a model).
*/
void checkCameraPlausible(const CameraModel &camera, const std::string &what);

/*! \brief An OpenCV YAML camera file's text (the format loadCameraFile() reads). \param camera The camera. */
std::string cameraYamlText(const CameraModel &camera);
/*!
  \brief Write cameraYamlText() to `path` atomically (core/files.h).
  \param path The file. \param camera The camera.
*/
void saveCameraYaml(const std::string &path, const CameraModel &camera);

} // namespace yawdepth
