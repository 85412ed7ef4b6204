// What the simulated arm did, for the motion rostests: its joints as the simulated
// controller publishes them on ~actual_joint_states (heard even while a test
// silences /joint_states), the commands sent to it and what the controller, by
// joint_trajectory_controller's rules, made of each (~command_outcomes).
#pragma once

#include <ros/ros.h>
#include <sensor_msgs/JointState.h>
#include <std_msgs/String.h>
#include <trajectory_msgs/JointTrajectory.h>

#include <algorithm>
#include <deque>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

namespace handeye {
namespace test {

class ArmWatch {
 public:
  explicit ArmWatch(const std::string& controller = "/arm_controller") {
    ros::NodeHandle nh;
    joints_sub_ = nh.subscribe<sensor_msgs::JointState>(
        controller + "/actual_joint_states", 200, [this](const sensor_msgs::JointStateConstPtr& m) {
          std::lock_guard<std::mutex> lock(mutex_);
          joints_.emplace_back(m->header.stamp.toSec(),
                               Eigen::Map<const Eigen::VectorXd>(m->position.data(), m->position.size()));
          while (joints_.size() > 3000) joints_.pop_front();  // 30 s at 100 Hz
        });
    commands_sub_ = nh.subscribe<trajectory_msgs::JointTrajectory>(
        controller + "/command", 20, [this](const trajectory_msgs::JointTrajectoryConstPtr& m) {
          std::lock_guard<std::mutex> lock(mutex_);
          commands_.emplace_back(ros::Time::now().toSec(), m->points.size());
        });
    outcomes_sub_ = nh.subscribe<std_msgs::String>(controller + "/command_outcomes", 20,
                                                   [this](const std_msgs::StringConstPtr& m) {
                                                     std::lock_guard<std::mutex> lock(mutex_);
                                                     outcomes_.push_back(m->data);
                                                   });
  }

  /// The arm's joints at time t, between the two joint states around it.
  std::optional<Eigen::VectorXd> at(double t) const {
    std::lock_guard<std::mutex> lock(mutex_);
    if (joints_.empty() || t < joints_.front().first) return std::nullopt;
    for (std::size_t k = 1; k < joints_.size(); ++k) {
      const auto& [t1, q1] = joints_[k];
      if (t1 < t) continue;
      const auto& [t0, q0] = joints_[k - 1];
      return Eigen::VectorXd(q0 + (q1 - q0) * ((t - t0) / std::max(t1 - t0, 1e-9)));
    }
    return joints_.back().second;
  }

  /// Whether the arm has been still (every joint within 1e-6 rad) for the last `seconds`.
  bool still_for(double seconds) const {
    std::lock_guard<std::mutex> lock(mutex_);
    if (joints_.size() < 2 || joints_.back().first - joints_.front().first < seconds) return false;
    for (auto it = joints_.rbegin(); it != joints_.rend() && it->first >= joints_.back().first - seconds; ++it)
      if ((it->second - joints_.back().second).cwiseAbs().maxCoeff() > 1e-6) return false;
    return true;
  }

  /// The largest joint change (rad) from time t to where the arm comes to rest (still
  /// for 0.5 s, waited for up to `timeout` s); none when the arm does not rest or t is unknown.
  std::optional<double> travel_after(double t, double timeout = 10.0) const {
    const ros::WallTime until = ros::WallTime::now() + ros::WallDuration(timeout);
    while (ros::ok() && !still_for(0.5) && ros::WallTime::now() < until) ros::WallDuration(0.02).sleep();
    const std::optional<Eigen::VectorXd> then = at(t);
    if (!still_for(0.5) || !then) return std::nullopt;
    std::lock_guard<std::mutex> lock(mutex_);
    return (joints_.back().second - *then).cwiseAbs().maxCoeff();
  }

  std::size_t commands() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return commands_.size();
  }
  /// When the latest command with no points (a hold) arrived, after the first `skip` commands.
  std::optional<double> hold_received(std::size_t skip = 0) const {
    std::lock_guard<std::mutex> lock(mutex_);
    for (std::size_t k = commands_.size(); k > skip; --k)
      if (commands_[k - 1].second == 0) return commands_[k - 1].first;
    return std::nullopt;
  }
  /// Commands the controller did not take as sent ("dropped: ...", "refused: ...", a partial drop).
  std::vector<std::string> not_taken_whole() const {
    std::lock_guard<std::mutex> lock(mutex_);
    std::vector<std::string> bad;
    for (const std::string& o : outcomes_)
      if (o != "accepted" && o != "hold") bad.push_back(o);
    return bad;
  }
  std::vector<std::string> outcomes() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return outcomes_;
  }

 private:
  mutable std::mutex mutex_;
  std::deque<std::pair<double, Eigen::VectorXd>> joints_;  // (stamp, positions in the controller's order)
  std::vector<std::pair<double, std::size_t>> commands_;   // (received, points)
  std::vector<std::string> outcomes_;
  ros::Subscriber joints_sub_, commands_sub_, outcomes_sub_;
};

}  // namespace test
}  // namespace handeye
