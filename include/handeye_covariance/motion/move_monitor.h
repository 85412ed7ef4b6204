// Watching one commanded move through the interfaces real drivers have: a
// trajectory sent to the controller, progress from joint states. The node feeds
// it joint states and the clock; it says when the arm has arrived, or why the
// move failed: the controller does not arrive in time, or joint states stop.
// No ROS: times are seconds on the caller's clock.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "handeye_covariance/motion/view_planner.h"

namespace handeye::motion {

struct MoveLimits {
  double arrival_tolerance = 0.005;  // rad, every joint, at the goal, once the trajectory's time is up
  /// The controller may take this long beyond the trajectory's duration.
  double arrival_allowance = 3.0;    // s
  /// Joint states older than this stop the move.
  double joint_states_timeout = 0.5; // s
};

enum class MoveStatus { Moving, Arrived, TimedOut, JointStatesStalled };
const char* to_string(MoveStatus status);  // "moving", "arrived", "timed_out", "joint_states_stalled"

class MoveMonitor {
 public:
  /// The move starts at `start_time` with the commanded `trajectory` (timed_move).
  MoveMonitor(std::vector<TrajectoryPoint> trajectory, double start_time, const MoveLimits& limits = {});

  /// A joint state at time t (the chain's joints, in order).
  void joint_state(double t, const Eigen::VectorXd& q);
  /// The status at `now`; once not Moving it stays.
  MoveStatus update(double now);
  /// Why the move stopped, with the numbers ("" while moving or arrived).
  const std::string& reason() const { return reason_; }
  /// The latest joints seen (the start's before any).
  const Eigen::VectorXd& position() const { return position_; }
  const std::vector<TrajectoryPoint>& trajectory() const { return trajectory_; }
  double deadline() const { return start_time_ + trajectory_.back().time + limits_.arrival_allowance; }

 private:
  std::vector<TrajectoryPoint> trajectory_;
  double start_time_;
  MoveLimits limits_;
  Eigen::VectorXd position_;
  std::optional<double> last_state_;
  MoveStatus status_ = MoveStatus::Moving;
  std::string reason_;
};

/// A trajectory that holds the arm where it is: one point at `q`, zero velocity,
/// reached at once (what Stop sends; joint_trajectory_controller then holds).
std::vector<TrajectoryPoint> hold_trajectory(const Eigen::VectorXd& q);

}  // namespace handeye::motion
