#include "handeye_covariance/ros/target_detector.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "target_detector");
  try {
    handeye::TargetDetectorNode node(ros::NodeHandle(), ros::NodeHandle("~"));
    ros::spin();
  } catch (const std::exception& e) {
    ROS_FATAL("target_detector: %s", e.what());
    return 1;
  }
  return 0;
}
