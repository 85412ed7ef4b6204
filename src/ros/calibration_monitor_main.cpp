// The calibration monitor node (publish.launch monitor:=true): ros/calibration_monitor_node.h.
#include <ros/ros.h>

#include "handeye_covariance/ros/calibration_monitor_node.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "handeye_monitor");
  handeye::CalibrationMonitorNode node(ros::NodeHandle(), ros::NodeHandle("~"));
  ros::AsyncSpinner spinner(2);  // detections and the diagnostics timer
  spinner.start();
  ros::waitForShutdown();
  return 0;
}
