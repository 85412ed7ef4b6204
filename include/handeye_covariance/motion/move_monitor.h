// Watching one commanded move through the interfaces real drivers have: a
// trajectory sent to the controller, progress judged from joint states alone.
// A speed-scaled controller (the UR driver's slider, a robot slowing near a
// person) runs the trajectory slower than planned, so the monitor does not time
// the move: it follows the arm along the planned path (the distance left to the
// goal) and stops the move when
//   - joint states stop coming (joint_states_timeout);
//   - the distance left stops shrinking: less than progress_step in stall_time,
//     or, near the move's ends where the planned speed is near zero, in twice
//     the time the trajectory itself takes at min_speed_scale to the next step
//     (the first one start_step) from start_step behind the latest progress: the
//     controller may still be finishing the previous move, whose last creep is
//     not this move's progress;
//   - the arm leaves the planned path by more than path_tolerance;
//   - it has not arrived by the trajectory's duration at min_speed_scale plus
//     arrival_allowance (a last bound).
// Arrived: every joint within arrival_tolerance of the goal and slower than
// settle_speed. No ROS: times are seconds on the caller's clock.
#pragma once

#include <deque>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "handeye_covariance/motion/trajectory.h"

namespace handeye::motion {

struct MoveLimits {
  double arrival_tolerance = 0.005;   // rad, every joint, at the goal
  double settle_speed = 0.01;         // rad/s, every joint, to count as arrived
  double stall_time = 0.8;            // s without progress along the path
  double progress_step = 1e-4;        // rad of path: progress (above joint states' noise)
  double start_step = 5e-4;           // rad of path: the move has begun (beyond a previous move's last creep)
  double min_speed_scale = 0.05;      // the slowest a controller may run the trajectory without being called stalled
  double path_tolerance = 0.05;       // rad, joint-space distance from the planned path
  double arrival_allowance = 3.0;     // s beyond the trajectory's duration at min_speed_scale
  double joint_states_timeout = 0.5;  // s
};

/// Throws HandEyeError naming the parameters when a limit is out of range.
void check_limits(const MoveLimits& limits);

enum class MoveStatus { Moving, Arrived, Stalled, LeftPath, TimedOut, JointStatesStalled };
/// "moving", "arrived", "stalled", "left_path", "timed_out", "joint_states_stalled"
const char* to_string(MoveStatus status);

class MoveMonitor {
 public:
  /// The move starts at `start_time` with the commanded `trajectory` (timed_move).
  /// Throws HandEyeError for an empty trajectory or limits that are not positive.
  MoveMonitor(std::vector<TrajectoryPoint> trajectory, double start_time, const MoveLimits& limits = {});

  /// A joint state at time t (the chain's joints, in order; other sizes are ignored).
  void joint_state(double t, const Eigen::VectorXd& q);
  /// The status at `now`; once not Moving it stays.
  MoveStatus update(double now);
  /// Why the move stopped, with the numbers ("" while moving or arrived).
  const std::string& reason() const { return reason_; }
  /// The latest joints seen (the start's before any).
  const Eigen::VectorXd& position() const { return position_; }
  const std::vector<TrajectoryPoint>& trajectory() const { return trajectory_; }
  /// The last bound: the trajectory's duration at min_speed_scale, plus the allowance.
  double deadline() const;
  /// The path length (joint space, rad) and how much of it the latest joints have covered.
  double path_length() const { return arc_.back(); }
  double covered() const { return covered_; }
  /// How long the monitor now waits for progress before it calls the arm stalled.
  double stall_window() const;

 private:
  /// The planned time at which the trajectory has covered `arc` of the path.
  double planned_time(double arc) const;

  std::vector<TrajectoryPoint> trajectory_;
  double start_time_;
  MoveLimits limits_;
  std::vector<double> arc_;                         // path length at each trajectory point
  std::vector<std::pair<double, double>> planned_;  // (time, arc covered) along the trajectory, finely
  Eigen::VectorXd position_;
  std::optional<double> last_state_;
  std::deque<std::pair<double, Eigen::VectorXd>> recent_;  // the last 0.1 s of joint states
  double covered_ = 0.0, off_path_ = 0.0;
  double mark_arc_ = 0.0, mark_time_ = 0.0;  // the latest progress: how far, when
  bool started_ = false;                     // progress seen since the start
  MoveStatus status_ = MoveStatus::Moving;
  std::string reason_;
};

}  // namespace handeye::motion
