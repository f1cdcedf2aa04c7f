// Camera calibration: ViSP's two models (without and with distortion), fitted by vpCalibration from
// OpenCV's result, and ViSP's camera file.
#include "camera_calibration_impl.h"
#include "quiet_visp.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <visp3/core/vpException.h>
#include <visp3/core/vpImagePoint.h>
#include <visp3/core/vpXmlParserCamera.h>
#include <visp3/vision/vpCalibration.h>
#include <yawdepth/core/files.h>
#include <yawdepth/error.h>

namespace yawdepth {
namespace calibration_detail {

namespace {

/* One vpCalibration per used view, with its board points and pixels. */
std::vector<vpCalibration> vispCalibrationTable(const CameraFit &fit, const std::vector<std::size_t> &used)
{
  std::vector<vpCalibration> table;
  for (std::size_t i : used) {
    vpCalibration calib;
    calib.clearPoint();
    if (fit.options.fix_aspect_ratio)
      calib.setAspectRatio(1.0);
    for (std::size_t j = 0; j < fit.object[i].size(); ++j) {
      vpImagePoint ip(fit.image[i][j].y, fit.image[i][j].x);
      calib.addPoint(fit.object[i][j].x, fit.object[i][j].y, fit.object[i][j].z, ip);
    }
    table.push_back(calib);
  }
  return table;
}

/* Reprojection RMS of ViSP's two models, each with its own poses (and of kdu, the inverse
   distortion), into result. */
void storeVispErrors(const CameraFit &fit, const std::vector<std::size_t> &used, const std::vector<vpCalibration> &table,
                     CameraCalibration &result)
{
  double s_wo = 0, s_w = 0, s_kdu = 0;
  std::size_t n = 0;
  const vpCameraParameters &cw = result.visp_with, &c0 = result.visp_without;
  for (std::size_t k = 0; k < used.size(); ++k) {
    const std::size_t i = used[k];
    const vpHomogeneousMatrix &M0 = table[k].cMo, &M1 = table[k].cMo_dist;
    for (std::size_t j = 0; j < fit.object[i].size(); ++j) {
      const double X = fit.object[i][j].x, Y = fit.object[i][j].y, Z = fit.object[i][j].z;
      const double u = fit.image[i][j].x, v = fit.image[i][j].y;
      auto proj = [&](const vpHomogeneousMatrix &M, double &x, double &y) {
        const double cx = M[0][0] * X + M[0][1] * Y + M[0][2] * Z + M[0][3];
        const double cy = M[1][0] * X + M[1][1] * Y + M[1][2] * Z + M[1][3];
        const double cz = M[2][0] * X + M[2][1] * Y + M[2][2] * Z + M[2][3];
        x = cx / cz;
        y = cy / cz;
      };
      double x, y;
      proj(M0, x, y);
      s_wo += std::pow(c0.get_u0() + c0.get_px() * x - u, 2) + std::pow(c0.get_v0() + c0.get_py() * y - v, 2);
      proj(M1, x, y);
      const double r2 = x * x + y * y;
      s_w += std::pow(cw.get_u0() + cw.get_px() * x * (1 + cw.get_kud() * r2) - u, 2) +
             std::pow(cw.get_v0() + cw.get_py() * y * (1 + cw.get_kud() * r2) - v, 2);
      // kdu: observed pixel to undistorted pixel, compared with the pinhole projection.
      const double xd = (u - cw.get_u0()) / cw.get_px(), yd = (v - cw.get_v0()) / cw.get_py();
      const double f = 1 + cw.get_kdu() * (xd * xd + yd * yd);
      s_kdu += std::pow(cw.get_u0() + cw.get_px() * xd * f - (cw.get_u0() + cw.get_px() * x), 2) +
               std::pow(cw.get_v0() + cw.get_py() * yd * f - (cw.get_v0() + cw.get_py() * y), 2);
      ++n;
    }
  }
  result.visp_rms_without = std::sqrt(s_wo / static_cast<double>(n));
  result.visp_rms_with = std::sqrt(s_w / static_cast<double>(n));
  result.visp_rms_kdu = std::sqrt(s_kdu / static_cast<double>(n));
}

} // namespace

/* ViSP's two models, fitted by vpCalibration as ViSP's calibration tool does, from OpenCV's
   result; a note instead when they cannot be. */
void fitVispModels(const CameraFit &fit, const OpenCvSolution &sol, const std::vector<std::size_t> &used,
                   CameraCalibration &result)
{
  try {
    const detail::QuietVisp quiet; // vpCalibration prints, and its gain is a static
    std::vector<vpCalibration> table = vispCalibrationTable(fit, used);
    vpCalibration::setLambda(0.5);
    vpCameraParameters cam;
    cam.initPersProjWithoutDistortion(sol.K.at<double>(0, 0), sol.K.at<double>(1, 1), sol.K.at<double>(0, 2),
                                      sol.K.at<double>(1, 2));
    double err = 0;
    if (vpCalibration::computeCalibrationMulti(vpCalibration::CALIB_VIRTUAL_VS, table, cam, err, false) != 0)
      throw Error("vpCalibration failed (model without distortion)");
    result.visp_without = cam;
    if (vpCalibration::computeCalibrationMulti(vpCalibration::CALIB_VIRTUAL_VS_DIST, table, cam, err, false) != 0)
      throw Error("vpCalibration failed (model with distortion)");
    result.visp_with = cam;
    storeVispErrors(fit, used, table, result);
    result.visp_fitted = std::isfinite(result.visp_rms_with) && std::isfinite(result.visp_rms_without);
    if (!result.visp_fitted)
      result.notes.emplace_back("ViSP models: non-finite fit");
  } catch (const Error &e) {
    result.notes.push_back(std::string("ViSP models not fitted: ") + e.what());
  } catch (const vpException &e) {
    result.notes.push_back("ViSP models not fitted: " + oneLine(e.getStringMessage()));
  }
}

} // namespace calibration_detail

std::string vispCameraXmlText(const CameraCalibration &calibration, const std::string &camera_name,
                              const std::string &additional_info)
{
  if (!calibration.visp_fitted)
    throw Error("ViSP camera file: the ViSP models were not fitted");
  // vpXmlParserCamera only writes to a path: a private folder, read back, then removed.
  namespace fs = std::filesystem;
  std::error_code ec;
  std::string templ = (fs::temp_directory_path(ec) / "yawdepth-xml-XXXXXX").string();
  if (ec)
    templ = "/tmp/yawdepth-xml-XXXXXX";
  std::vector<char> buf(templ.begin(), templ.end());
  buf.push_back('\0');
  if (!::mkdtemp(buf.data()))
    throw Error(std::string("ViSP camera file: cannot create a temporary folder (") + std::strerror(errno) + ")");
  const fs::path dir(buf.data());
  struct RemoveDir {
    fs::path dir;
    ~RemoveDir()
    {
      std::error_code e;
      fs::remove_all(dir, e);
    }
  } cleanup{dir};
  const std::string tmp = (dir / "camera.xml").string();
  const std::string name = camera_name.empty() ? std::string("Camera") : camera_name;
  const unsigned w = calibration.camera.width(), h = calibration.camera.height();
  try {
    const detail::QuietVisp quiet; // save() prints "Found camera with name ..."
    vpXmlParserCamera xml;
    if (xml.save(calibration.visp_without, tmp, name, w, h) != vpXmlParserCamera::SEQUENCE_OK)
      throw Error("ViSP camera file: cannot write the model without distortion");
    vpXmlParserCamera xml2;
    if (xml2.save(calibration.visp_with, tmp, name, w, h, additional_info) != vpXmlParserCamera::SEQUENCE_OK)
      throw Error("ViSP camera file: cannot write the model with distortion");
  } catch (const vpException &e) {
    throw Error("ViSP camera file: " + calibration_detail::oneLine(e.getStringMessage()));
  }
  return readTextFile(tmp, std::size_t(16) << 20);
}

void saveVispCameraXml(const std::string &path, const CameraCalibration &calibration, const std::string &camera_name,
                       const std::string &additional_info)
{
  writeFileAtomically(path, vispCameraXmlText(calibration, camera_name, additional_info));
}
} // namespace yawdepth
