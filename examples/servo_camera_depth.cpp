/*
  servo_camera_depth: live depth of an AprilTag's corners from a real camera and the robot's
  odometry, with yawdepth::DepthProvider, as a servo loop would use it.

    servo_camera_depth --camera CAM.xml|yaml --motion motion.csv --tag 36h11:SIZE
                       [--rig rig.yaml] [--video DEVICE_INDEX|FILE] [--prior 1.0]

  Images: the motion log's `image` column (a recorded folder), or --video (an OpenCV capture:
  a V4L2 device index such as 0, or a video file); frame k of the capture takes the motion-log row
  of frame k. Odometry: the motion log CSV (frame,x,y,z,heading,yaw; see docs/formats.md). Each frame
  prints the tag corners' ids with the depth handed to vpFeaturePoint, its 1-sigma, the
  estimator's status, and whether it is the estimate (*) or still the prior.
*/
#include <cstdio>
#include <string>
#include <vector>

#include <opencv2/videoio.hpp>
#include <yawdepth/camera/camera_file.h>
#include <yawdepth/error.h>
#include <yawdepth/features/detector.h>
#include <yawdepth/io/files.h>
#include <yawdepth/servo/depth_provider.h>

int main(int argc, char **argv)
{
  std::string camera_path, motion_path, tag, rig_path, video;
  yawdepth::DepthProviderOptions o;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i], v = argv[i + 1];
    if (a == "--camera") camera_path = v;
    else if (a == "--motion") motion_path = v;
    else if (a == "--tag") tag = v;
    else if (a == "--rig") rig_path = v;
    else if (a == "--video") video = v;
    else if (a == "--prior") o.prior_depth = std::stod(v);
    else {
      std::fprintf(stderr, "servo_camera_depth: unknown option %s\n", a.c_str());
      return 2;
    }
  }
  if (camera_path.empty() || motion_path.empty() || tag.empty()) {
    std::fprintf(stderr, "usage: servo_camera_depth --camera C --motion M --tag FAMILY:SIZE [--rig R] [--video V] [--prior Z]\n");
    return 2;
  }
  try {
    const yawdepth::CameraModel camera = yawdepth::loadCameraFile(camera_path);
    yawdepth::YawRig rig;
    std::optional<double> fixed_yaw;
    if (!rig_path.empty()) {
      const yawdepth::RigFile rf = yawdepth::readRigFile(rig_path);
      rig = yawdepth::rigOf(rf);
      fixed_yaw = rf.yaw;
    }
    yawdepth::MotionLog log = yawdepth::readMotionCsv(motion_path, fixed_yaw);
    if (!rig_path.empty())
      yawdepth::applyRigFile(yawdepth::readRigFile(rig_path), log.samples);
    yawdepth::PatternDetector detector(yawdepth::PatternSpec::parse("apriltag:" + tag));
    detector.setCamera(camera);
    yawdepth::DepthProvider depth(camera, rig, o);
    cv::VideoCapture cap;
    if (!video.empty()) {
      const bool index = video.find_first_not_of("0123456789") == std::string::npos;
      if (!(index ? cap.open(std::stoi(video)) : cap.open(video)))
        throw yawdepth::Error("cannot open video " + video);
    } else if (log.images.empty()) {
      throw yawdepth::Error("the motion log has no image column: give --video");
    }
    for (std::size_t k = 0; k < log.samples.size(); ++k) {
      cv::Mat image;
      if (cap.isOpened()) {
        if (!cap.read(image))
          break;
      } else {
        image = yawdepth::readGrayImage(log.images[k]);
      }
      const yawdepth::FrameDetection det = detector.detect(image, log.samples[k].frame);
      std::vector<std::pair<long, vpImagePoint>> points;
      for (const yawdepth::FeatureObservation &f : det.features)
        if (f.id % 5 != 0) // corners only (id 5t is the tag's centre)
          points.emplace_back(f.id, vpImagePoint(f.v, f.u));
      depth.update(log.samples[k], points);
      std::printf("frame %ld:", log.samples[k].frame);
      if (!det.found)
        std::printf(" (%s)", det.reason.c_str());
      for (const auto &p : points) {
        const yawdepth::FeatureDepth f = depth.info(p.first);
        std::printf("  %ld Z=%.4f+-%.4f %s%s", p.first, f.depth, f.sigma, yawdepth::toString(f.status),
                    f.converged ? "*" : " (prior)");
      }
      std::printf("\n");
      std::fflush(stdout);
    }
  } catch (const std::exception &e) {
    std::fprintf(stderr, "servo_camera_depth: %s\n", e.what());
    return 1;
  }
  return 0;
}
