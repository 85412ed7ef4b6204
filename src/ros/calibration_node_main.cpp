#include "handeye_covariance/ros/calibration_node.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "handeye_calibration");
  try {
    handeye::CalibrationNode node(ros::NodeHandle(), ros::NodeHandle("~"));
    ros::MultiThreadedSpinner(2).spin();  // /suggest_pose may take a while; /calibrate does not wait for it
  } catch (const std::exception& e) {
    ROS_FATAL("handeye_calibration: %s", e.what());
    return 1;
  }
  return 0;
}
