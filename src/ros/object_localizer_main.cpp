#include "handeye_covariance/ros/object_localizer.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "object_localizer");
  try {
    handeye::ObjectLocalizer node(ros::NodeHandle(), ros::NodeHandle("~"));
    ros::spin();
  } catch (const std::exception& e) {
    ROS_FATAL("object_localizer: %s", e.what());
    return 1;
  }
  return 0;
}
