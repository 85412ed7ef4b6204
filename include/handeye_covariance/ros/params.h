// Reading a ROS parameter with a default.
#pragma once

#include <ros/node_handle.h>

#include <string>

namespace handeye {

template <typename T>
T param(const ros::NodeHandle& nh, const std::string& name, const T& fallback) {
  T value;
  return nh.getParam(name, value) ? value : fallback;
}

}  // namespace handeye
