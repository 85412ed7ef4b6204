#include "handeye_covariance/ros/calibration_node.h"
#include "handeye_covariance/ros/shutdown_request.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "handeye_calibration", ros::init_options::NoSigintHandler);  // shutdown_request.h
  // Held past the catch: when the last handle goes, ROS shuts down its logging, and ROS_FATAL would print nothing.
  ros::NodeHandle node_handle, private_node_handle("~");
  try {
    handeye::CalibrationNode node(node_handle, private_node_handle);
    // Two threads: /suggest_pose may take a while; /calibrate does not wait for it.
    handeye::spin_until_shutdown(2, [&] { node.stop_for_shutdown(); });
  } catch (const std::exception& e) {
    ROS_FATAL("handeye_calibration: %s", e.what());
    return 1;
  }
  return 0;
}
