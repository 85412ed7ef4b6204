// Reading a ROS parameter with a default.
#pragma once

#include <ros/node_handle.h>

#include <type_traits>

#include <string>

#include "handeye_covariance/io/yaml_io.h"
#include "handeye_covariance/session/session_config.h"

namespace handeye {

template <typename T>
T param(const ros::NodeHandle& nh, const std::string& name, const T& fallback) {
  T value;
  return nh.getParam(name, value) ? value : fallback;
}

/// The session settings from private parameters (same keys as the YAML config).
inline void load_session_config(const ros::NodeHandle& nh, SessionConfig& config) {
  for_each_setting(config, [&](const char* key, auto& member, double scale) {
    using T = std::decay_t<decltype(member)>;
    if constexpr (std::is_same_v<T, Setup>) {
      bool eye_on_hand = true;
      if (nh.getParam(key, eye_on_hand)) member = setup_from_eye_on_hand(eye_on_hand);
    } else {
      T value;
      if (nh.getParam(key, value)) {
        if constexpr (std::is_same_v<T, double>) {
          member = value * scale;
        } else {
          member = value;
        }
      }
    }
  });
}

/// A node's settings: ~parameters over the defaults, the default file names as
/// easy_handeye's (~/.ros/handeye_covariance/<namespace>[_samples].yaml).
inline SessionConfig node_session_config(const ros::NodeHandle& private_node) {
  SessionConfig config;
  load_session_config(private_node, config);
  const std::string dir = "~/.ros/handeye_covariance/";
  if (config.calibration_file.empty()) config.calibration_file = dir + config.name() + ".yaml";
  if (config.session_file.empty()) config.session_file = dir + config.name() + "_samples.yaml";
  config.calibration_file = io::expand_home(config.calibration_file);
  return config;
}

}  // namespace handeye
