#include "handeye_covariance/ros/target_detector.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "target_detector");
  // Held past the catch: when the last handle goes, ROS shuts down its logging, and ROS_FATAL would print nothing.
  ros::NodeHandle node_handle, private_node_handle("~");
  try {
    handeye::TargetDetectorNode node(node_handle, private_node_handle);
    ros::spin();
  } catch (const std::exception& e) {
    ROS_FATAL("target_detector: %s", e.what());
    return 1;
  }
  return 0;
}
