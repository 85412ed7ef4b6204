// Helpers for the rostest clients: waiting on topics and services with deadlines.
#pragma once

#include <gtest/gtest.h>
#include <ros/ros.h>

#include <cstdlib>
#include <filesystem>
#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <functional>
#include <string>

#include <geometry_msgs/PoseStamped.h>

#include "handeye_covariance/io/yaml_io.h"
#include "handeye_covariance/ros/messages.h"
#include "scratch_directory.h"

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

/// The X display for one rviz test at a time, held for the test's life: catkin_make
/// runs two rostests at once and scripts/test gives them one Xvfb, where the windows of
/// two rvizes overlap and the screenshot test looks for its colour anywhere on screen.
class DisplayLock {
 public:
  DisplayLock() : fd_(::open("/tmp/handeye_covariance_rviz_display.lock", O_CREAT | O_RDWR, 0666)) {
    if (fd_ < 0 || ::flock(fd_, LOCK_EX) != 0) ADD_FAILURE() << "cannot lock /tmp/handeye_covariance_rviz_display.lock";
  }
  ~DisplayLock() {
    if (fd_ >= 0) ::close(fd_);  // releases the lock
  }
  DisplayLock(const DisplayLock&) = delete;
  DisplayLock& operator=(const DisplayLock&) = delete;

 private:
  int fd_;
};

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

/// Loads the samples file `samples_path` into the node of `ns` with sample 3 paired with
/// sample 0's pattern pose (a detection with the wrong stamp); returns the node's sample
/// count, or -1 after a test failure naming what went wrong.
inline int load_with_wrong_detection(const std::string& ns, const std::string& samples_path) {
  SampleSet corrupted = io::read_samples(samples_path);
  corrupted.samples[3].T_camera_pattern = corrupted.samples[0].T_camera_pattern;
  LoadSamples load;
  load.request.path = scratch_directory() + "/corrupted_samples.yaml";
  io::write_file_atomically(load.request.path, io::format_samples(corrupted));
  if (!call(ns + "load_samples", load) || !load.response.success) {
    ADD_FAILURE() << ns << "load_samples " << load.request.path << ": " << load.response.message;
    return -1;
  }
  return load.response.samples;
}

}  // namespace test
}  // namespace handeye
