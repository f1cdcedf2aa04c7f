/*
  servo_depths_client: the servo side of yawdepth_node's `~depths` service (docs/ros.md, "Servo"),
  as a visp_ros / vision_visp user's node would have it. It tracks corners in the camera's images
  with ViSP's vpKltOpencv (its own ids), asks yawdepth_node for their depths once per image (one
  control period: the image's stamp, the ids and their pixels), and builds the vpFeaturePoint's of an
  IBVS loop with them (x, y from the pixel, Z the depth: the estimate once converged, the prior
  before). The control law itself is the user's (vpServo); this prints what it would be given.

    servo_depths_client image:=/camera/image_raw [_image_transport:=compressed] [_service:=/yawdepth_node/depths]
                        [_features:=20] [_csv:=depths.csv] [_max_images:=0]

  With _csv, every answer is written as `stamp,id,u,v,depth,sigma,status,converged` (the ROS test
  checks it against the truth). Exits 1 with a one-line error for a bad parameter.
*/
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <string>
#include <vector>

#include <cv_bridge/cv_bridge.h>
#include <opencv2/imgcodecs.hpp>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>
#include <visp3/core/vpCameraParameters.h>
#include <visp3/klt/vpKltOpencv.h>
#include <visp3/visual_features/vpFeatureBuilder.h>
#include <visp3/visual_features/vpFeaturePoint.h>

#include <yawdepth/FeatureDepths.h> // yawdepth_node's service, generated from its srv/FeatureDepths.srv

namespace {

class ServoDepthsClient {
public:
  ServoDepthsClient() : pnh_("~")
  {
    pnh_.param("features", features_, 20);
    pnh_.param("max_images", max_images_, 0);
    std::string transport, service, csv;
    pnh_.param<std::string>("image_transport", transport, "raw");
    pnh_.param<std::string>("service", service, "/yawdepth_node/depths");
    pnh_.param<std::string>("csv", csv, "");
    if (features_ < 1)
      throw std::runtime_error("~features: must be at least 1");
    if (transport != "raw" && transport != "compressed")
      throw std::runtime_error("~image_transport: '" + transport + "' (raw or compressed)");
    if (!csv.empty()) {
      csv_.open(csv);
      if (!csv_)
        throw std::runtime_error("~csv: cannot write " + csv);
      csv_ << "stamp,id,u,v,depth,sigma,status,converged\n";
      csv_.precision(10); // depths, sigmas and pixels
    }
    client_ = nh_.serviceClient<yawdepth::FeatureDepths>(service);
    const std::string image = nh_.resolveName("image");
    info_sub_ = nh_.subscribe(ros::names::parentNamespace(image) + "/camera_info", 1, &ServoDepthsClient::onInfo, this);
    if (transport == "compressed")
      compressed_sub_ = nh_.subscribe(image + "/compressed", 5, &ServoDepthsClient::onCompressed, this);
    else
      image_sub_ = nh_.subscribe(image, 5, &ServoDepthsClient::onImage, this);
    // ViSP's KLT tracker, as a servo node tracks its points.
    tracker_.setMaxFeatures(features_);
    tracker_.setWindowSize(21);
    tracker_.setQuality(0.01);
    tracker_.setMinDistance(20);
    tracker_.setHarrisFreeParameter(0.04);
    tracker_.setBlockSize(9);
    tracker_.setUseHarris(1);
    tracker_.setPyramidLevels(3);
  }

private:
  void onInfo(const sensor_msgs::CameraInfoConstPtr &m)
  {
    if (!have_camera_) // the pinhole part: enough for vpFeaturePoint's x, y here (an undistorted camera)
      camera_.initPersProjWithoutDistortion(m->K[0], m->K[4], m->K[2], m->K[5]);
    have_camera_ = true;
  }

  void onImage(const sensor_msgs::ImageConstPtr &m)
  {
    period(m->header, cv_bridge::toCvShare(m, "mono8")->image);
  }

  void onCompressed(const sensor_msgs::CompressedImageConstPtr &m)
  {
    const cv::Mat gray = cv::imdecode(m->data, cv::IMREAD_GRAYSCALE);
    if (gray.empty()) {
      ROS_ERROR_THROTTLE(2, "servo_depths_client: an image OpenCV cannot decode");
      return;
    }
    period(m->header, gray);
  }

  /* One control period: track, ask for the depths, build the features. */
  void period(const std_msgs::Header &header, const cv::Mat &gray)
  {
    if (!have_camera_ || (max_images_ > 0 && images_ >= max_images_))
      return;
    ++images_;
    if (!started_ || tracker_.getNbFeatures() < features_ / 2) {
      tracker_.initTracking(gray); // vpKltOpencv numbers its points from 0 again: a new generation
      ++generation_;
      started_ = true;
    } else {
      tracker_.track(gray);
    }
    yawdepth::FeatureDepths call;
    call.request.header = header;
    for (int i = 0; i < tracker_.getNbFeatures(); ++i) {
      long id = 0;
      float u = 0, v = 0;
      tracker_.getFeature(i, id, u, v);
      // Ids never reused: a re-detected point is a new feature for yawdepth_node.
      call.request.ids.push_back(generation_ * kIdsPerGeneration + id);
      call.request.u.push_back(u);
      call.request.v.push_back(v);
    }
    if (!client_.call(call)) {
      ROS_WARN_THROTTLE(2, "servo_depths_client: %s did not answer", client_.getService().c_str());
      return;
    }
    const yawdepth::FeatureDepths::Response &r = call.response;
    if (!r.error.empty()) {
      ROS_WARN_THROTTLE(2, "servo_depths_client: %s", r.error.c_str());
      return;
    }
    // The IBVS features: x, y from the pixel, Z from yawdepth.
    std::vector<vpFeaturePoint> s(r.depth.size());
    int converged = 0;
    for (std::size_t i = 0; i < r.depth.size(); ++i) {
      vpFeatureBuilder::create(s[i], camera_, vpImagePoint(call.request.v[i], call.request.u[i]));
      s[i].set_Z(r.depth[i]);
      converged += r.converged[i] ? 1 : 0;
      if (csv_.is_open()) // the stamp exactly, as sec.nsec
        csv_ << header.stamp.sec << '.' << std::setw(9) << std::setfill('0') << header.stamp.nsec << std::setfill(' ')
             << ',' << call.request.ids[i] << ',' << call.request.u[i] << ','
             << call.request.v[i] << ',' << r.depth[i] << ',' << r.sigma[i] << ',' << r.status[i] << ','
             << (r.converged[i] ? 1 : 0) << '\n';
    }
    std::vector<double> z;
    for (const vpFeaturePoint &f : s)
      z.push_back(f.get_Z());
    std::sort(z.begin(), z.end());
    ROS_INFO_THROTTLE(1, "servo_depths_client: t = %.3f s: %zu features, %d converged, median Z %.3f m",
                      header.stamp.toSec(), s.size(), converged, z.empty() ? 0.0 : z[z.size() / 2]);
  }

  ros::NodeHandle nh_, pnh_;
  ros::Subscriber info_sub_, image_sub_, compressed_sub_;
  ros::ServiceClient client_;
  vpKltOpencv tracker_;
  vpCameraParameters camera_;
  bool have_camera_ = false, started_ = false;
  int features_ = 20, max_images_ = 0, images_ = 0;
  static constexpr long kIdsPerGeneration = 1000000;
  long generation_ = 0;
  std::ofstream csv_;
};

} // namespace

int main(int argc, char **argv)
{
  ros::init(argc, argv, "servo_depths_client");
  try {
    ServoDepthsClient client;
    ros::spin();
  } catch (const std::exception &e) {
    std::fprintf(stderr, "servo_depths_client: %s\n", e.what());
    return 1;
  }
  return 0;
}
