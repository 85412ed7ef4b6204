// A commanded joint trajectory, as a trajectory controller takes it, without ROS:
// the points of one move (timed_move), what is sent to the controller (a
// ROS-free trajectory_msgs/JointTrajectory: TrajectoryCommand), and the spline
// between two points that ros_controllers' joint_trajectory_controller follows
// (SplineSegment). Times are seconds, joints in rad (or m), in the arm's chain order.
// The rules a controller applies to a command are docs/motion.md's.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

namespace handeye::motion {

class Arm;

/// One point of a trajectory: velocity and acceleration are optional (size 0: not
/// given), as in trajectory_msgs/JointTrajectoryPoint.
struct TrajectoryPoint {
  double time = 0.0;  // s from the trajectory's start
  Eigen::VectorXd position, velocity, acceleration;
};

/// How fast a move may be: the peak speed of each joint is `speed_fraction` of its
/// URDF velocity limit; its peak acceleration at most `max_acceleration`, or the
/// joint's own entry of `joint_acceleration` when given (rad/s^2).
struct MoveTiming {
  double speed_fraction = 0.1;
  double max_acceleration = 1.5;              // rad/s^2 (86 deg/s^2), every joint
  std::vector<double> joint_acceleration;     // rad/s^2 per joint (e.g. MoveIt's joint_limits); empty: none
  double dt = 0.1;                            // s between points
  /// The bound of joint j (the smaller of the two when both are given).
  double acceleration(int j) const;
};

/// Throws HandEyeError naming the parameter when a bound is out of range.
void check_timing(const MoveTiming& timing);

/// A timed straight joint-space move: a quintic time scaling (zero velocity and
/// acceleration at both ends), as long as the slowest joint needs so that neither
/// its peak speed (15/8 of the mean) nor its peak acceleration (10/sqrt(3) L/T^2)
/// exceeds `timing`. Points every dt with position, velocity and acceleration.
/// Throws HandEyeError for a speed fraction outside (0, 1] or a bound that is not positive.
std::vector<TrajectoryPoint> timed_move(const Arm& arm, const Eigen::VectorXd& from, const Eigen::VectorXd& to,
                                        const MoveTiming& timing);

/// What is sent to a trajectory controller's `command` topic.
struct TrajectoryCommand {
  double stamp = 0.0;  // s on the controller's clock; 0: "start now" (when it is received)
  std::vector<std::string> joint_names;
  std::vector<TrajectoryPoint> points;  // none: "hold where you are"
};

/// The move for the arm's joints, to start when received (a zero stamp).
TrajectoryCommand move_command(const Arm& arm, const std::vector<TrajectoryPoint>& trajectory);
/// Stop: a command with no points, which joint_trajectory_controller takes as "hold
/// the current position" whatever it was doing. (One point at time 0 is dropped as
/// "in the past", and the running trajectory goes on.)
TrajectoryCommand hold_command(const Arm& arm);

/// The joints' state at a time on a trajectory.
struct JointState {
  Eigen::VectorXd position, velocity, acceleration;
};

/// The spline joint_trajectory_controller runs between two points over [start, end]:
/// linear with positions only, cubic with velocities at both ends, quintic with
/// accelerations too. Before `start` it is at its start; after `end`, at rest at its end.
class SplineSegment {
 public:
  SplineSegment(double start, const TrajectoryPoint& from, double end, const TrajectoryPoint& to);
  double start() const { return start_; }
  double end() const { return end_; }
  JointState sample(double t) const;

 private:
  double start_, end_;
  Eigen::MatrixXd coefficients_;  // joints x 6: p(s) = sum_k c_k s^k, s = t - start
};

}  // namespace handeye::motion
