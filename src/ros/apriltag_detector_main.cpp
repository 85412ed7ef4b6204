#include "handeye_covariance/ros/apriltag_detector.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "apriltag_detector");
  try {
    handeye::ApriltagDetectorNode node(ros::NodeHandle(), ros::NodeHandle("~"));
    ros::spin();
  } catch (const std::exception& e) {
    ROS_FATAL("apriltag_detector: %s", e.what());
    return 1;
  }
  return 0;
}
