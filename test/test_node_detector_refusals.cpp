// The real target_detector node fed bad camera input (detector_refusals.test).
// Its refusals are read where a user sees them: the log, on /rosout.
#include <cv_bridge/cv_bridge.h>
#include <gtest/gtest.h>
#include <image_transport/image_transport.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Log.h>
#include <sensor_msgs/image_encodings.h>

#include <opencv2/imgproc.hpp>

#include <mutex>

#include "handeye_covariance/simulation/simulation.h"
#include "handeye_covariance/ros/messages.h"
#include "handeye_covariance/ros/msg_conversion.h"
#include "handeye_covariance/simulation/pattern_renderer.h"
#include "node_test_helpers.h"

namespace handeye {
namespace {

class Detector {
 public:
  Detector() : transport_(nh_) {
    image_pub_ = transport_.advertise("/refusals/image_raw", 2);
    info_pub_ = nh_.advertise<sensor_msgs::CameraInfo>("/refusals/camera_info", 2);
    log_sub_ = nh_.subscribe<rosgraph_msgs::Log>("/rosout", 100, [this](const rosgraph_msgs::Log::ConstPtr& m) {
      std::lock_guard<std::mutex> lock(mutex_);
      if (m->name.find("target_detector") != std::string::npos) log_.push_back(m->msg);
    });
    detections_sub_ = nh_.subscribe<TagDetectionArray>("/refusals/tag_detections", 10, [this](const TagDetectionArray::ConstPtr& m) {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!m->detections.empty()) ++detections_;
    });
    spinner_.start();
    EXPECT_TRUE(test::wait_for([&] { return image_pub_.getNumSubscribers() > 0 && info_pub_.getNumSubscribers() > 0; }, 20.0));
  }

  /// Sends the image (and the info, unless null) until the log has a line with `needle`.
  bool logs(const cv::Mat& image, const sensor_msgs::CameraInfo* info, const std::string& needle) {
    return test::wait_for([&] {
      send(image, info);
      std::lock_guard<std::mutex> lock(mutex_);
      for (const std::string& line : log_) {
        if (line.find(needle) != std::string::npos) return true;
      }
      return false;
    }, 8.0);  // the detector throttles each message to one per 5 s
  }

  bool detects(const cv::Mat& image, const sensor_msgs::CameraInfo& info) {
    return test::wait_for([&] {
      send(image, &info);
      std::lock_guard<std::mutex> lock(mutex_);
      return detections_ > 0;
    }, 10.0);
  }

  std::string log() {
    std::lock_guard<std::mutex> lock(mutex_);
    std::string all;
    for (const std::string& line : log_) all += line + "\n";
    return all;
  }

 private:
  void send(const cv::Mat& image, const sensor_msgs::CameraInfo* info) {
    std_msgs::Header header;
    header.stamp = ros::Time::now();
    header.frame_id = "camera_optical_frame";
    const sensor_msgs::ImagePtr msg = cv_bridge::CvImage(header, sensor_msgs::image_encodings::MONO8, image).toImageMsg();
    if (info) {
      sensor_msgs::CameraInfo stamped = *info;
      stamped.header = header;
      info_pub_.publish(stamped);
      ros::WallDuration(0.05).sleep();  // the info first, as a driver sends it
    }
    image_pub_.publish(msg);
    ros::WallDuration(0.1).sleep();
  }

  ros::NodeHandle nh_;
  image_transport::ImageTransport transport_;
  image_transport::Publisher image_pub_;
  ros::Publisher info_pub_;
  ros::Subscriber log_sub_, detections_sub_;
  ros::AsyncSpinner spinner_{1};
  std::mutex mutex_;
  std::vector<std::string> log_;
  int detections_ = 0;
};

TEST(ApriltagDetector, BadCameraInputIsLoggedWithTheReasonAndGoodInputStillWorks) {
  Detector detector;
  const CameraModel camera = simulated_camera();
  const PatternRenderer renderer(single_tag_layout(0, 0.1), camera);
  Rng rng(2);
  const cv::Mat image = renderer.render(random_view(rng, ViewpointOptions{}), rng);  // a view the rig would have
  const sensor_msgs::CameraInfo good = conversions::to_camera_info(camera);

  EXPECT_TRUE(detector.logs(image, nullptr, "no usable CameraInfo on")) << detector.log();
  sensor_msgs::CameraInfo uncalibrated = good;
  uncalibrated.K.fill(0.0);
  EXPECT_TRUE(detector.logs(image, &uncalibrated, "not calibrated")) << detector.log();
  sensor_msgs::CameraInfo fisheye = good;
  fisheye.distortion_model = "equidistant";
  EXPECT_TRUE(detector.logs(image, &fisheye, "equidistant")) << detector.log();
  cv::Mat half;
  cv::resize(image, half, cv::Size(image.cols / 2, image.rows / 2));
  EXPECT_TRUE(detector.logs(half, &good, "but the CameraInfo says")) << detector.log();
  EXPECT_TRUE(detector.detects(image, good)) << detector.log();
}

}  // namespace
}  // namespace handeye

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_detector_refusals");
  return RUN_ALL_TESTS();
}
