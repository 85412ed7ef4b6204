#include "handeye_covariance/ros/calibration_node.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "handeye_calibration");
  // Held past the catch: when the last handle goes, ROS shuts down its logging, and ROS_FATAL would print nothing.
  ros::NodeHandle node_handle, private_node_handle("~");
  try {
    handeye::CalibrationNode node(node_handle, private_node_handle);
    ros::MultiThreadedSpinner(2).spin();  // /suggest_pose may take a while; /calibrate does not wait for it
  } catch (const std::exception& e) {
    ROS_FATAL("handeye_calibration: %s", e.what());
    return 1;
  }
  return 0;
}
