// Helpers for the rostest clients: waiting on topics and services with deadlines.
#pragma once

#include <gtest/gtest.h>
#include <ros/ros.h>

#include <cstdlib>
#include <filesystem>
#include <functional>
#include <string>

#include <geometry_msgs/PoseStamped.h>

#include "handeye_covariance/ros/messages.h"

namespace handeye {
namespace test {

/// Spins until `done()` or `seconds` of wall time pass; returns done().
inline bool wait_for(const std::function<bool()>& done, double seconds) {
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(seconds);
  while (ros::ok() && !done() && ros::WallTime::now() < deadline) {
    ros::spinOnce();
    ros::WallDuration(0.02).sleep();
  }
  return done();
}

/// A directory of this test process's own under /tmp/handeye_covariance_rostest, made on
/// first use. catkin_make runs two rostests at once (-j of the core count): a fixed file
/// name shared by two clients is overwritten under the other's feet.
inline const std::string& scratch_directory() {
  static const std::string directory = [] {
    std::filesystem::create_directories("/tmp/handeye_covariance_rostest");
    std::string pattern = "/tmp/handeye_covariance_rostest/client-XXXXXX";
    if (::mkdtemp(pattern.data()) == nullptr) {
      ADD_FAILURE() << "mkdtemp(" << pattern << ") failed: free space in /tmp";
      std::abort();
    }
    return pattern;
  }();
  return directory;
}

/// Keeps the latest ~status message.
struct StatusWatcher {
  CalibrationStatus latest;
  bool received = false;
  ros::Subscriber subscriber;
  explicit StatusWatcher(const std::string& topic) {
    ros::NodeHandle nh;
    subscriber = nh.subscribe<CalibrationStatus>(topic, 10, [this](const CalibrationStatus::ConstPtr& msg) {
      latest = *msg;
      received = true;
    });
  }
};

/// Keeps the simulated rig's true X and Y (latched on /rig_simulator/truth and pattern_truth).
struct TruthWatcher {
  geometry_msgs::PoseStamped truth, pattern;
  bool received = false, pattern_received = false;
  ros::Subscriber subscriber, pattern_subscriber;
  TruthWatcher() {
    ros::NodeHandle nh;
    subscriber = nh.subscribe<geometry_msgs::PoseStamped>("/rig_simulator/truth", 1, [this](const auto& msg) {
      truth = *msg;
      received = true;
    });
    pattern_subscriber = nh.subscribe<geometry_msgs::PoseStamped>("/rig_simulator/pattern_truth", 1, [this](const auto& msg) {
      pattern = *msg;
      pattern_received = true;
    });
  }
};

template <typename Service>
bool call(const std::string& name, Service& srv) {
  if (!ros::service::waitForService(name, ros::Duration(20.0))) {
    ADD_FAILURE() << "service " << name << " did not come up";
    return false;
  }
  const bool ok = ros::service::call(name, srv);
  EXPECT_TRUE(ok) << "call to " << name << " failed";
  return ok;
}

}  // namespace test
}  // namespace handeye
