#include "handeye_covariance/motion/move_monitor.h"

#include "handeye_covariance/core/errors.h"

namespace handeye::motion {

const char* to_string(MoveStatus status) {
  switch (status) {
    case MoveStatus::Moving: return "moving";
    case MoveStatus::Arrived: return "arrived";
    case MoveStatus::TimedOut: return "timed_out";
    case MoveStatus::JointStatesStalled: return "joint_states_stalled";
  }
  return "unknown";
}

MoveMonitor::MoveMonitor(std::vector<TrajectoryPoint> trajectory, double start_time, const MoveLimits& limits)
    : trajectory_(std::move(trajectory)), start_time_(start_time), limits_(limits) {
  if (trajectory_.empty())
    throw HandEyeError(ErrorCode::NoData, "an empty trajectory", "MoveMonitor", "plan a move first (timed_move)");
  position_ = trajectory_.front().position;
}

void MoveMonitor::joint_state(double t, const Eigen::VectorXd& q) {
  if (q.size() != position_.size()) return;  // another chain's message: not ours
  position_ = q;
  last_state_ = t;
}

MoveStatus MoveMonitor::update(double now) {
  if (status_ != MoveStatus::Moving) return status_;
  const Eigen::VectorXd& goal = trajectory_.back().position;
  const double off = (position_ - goal).cwiseAbs().maxCoeff();
  // Arrived: the trajectory's time is up and the latest joints are at the goal
  // (near the goal earlier, the arm is still moving).
  if (last_state_ && *last_state_ >= start_time_ + trajectory_.back().time && off <= limits_.arrival_tolerance) {
    status_ = MoveStatus::Arrived;
    return status_;
  }
  const double since = now - last_state_.value_or(start_time_);
  if (since > limits_.joint_states_timeout) {
    status_ = MoveStatus::JointStatesStalled;
    reason_ = "no joint states for " + number_text(since, 3) + " s (more than " +
              number_text(limits_.joint_states_timeout, 2) + " s) during the move";
  } else if (now > deadline()) {
    status_ = MoveStatus::TimedOut;
    reason_ = "the controller did not arrive within " + number_text(deadline() - start_time_, 3) +
              " s: a joint is still " + number_text(off * 180.0 / M_PI, 3) + " deg from the goal (tolerance " +
              number_text(limits_.arrival_tolerance * 180.0 / M_PI, 3) + " deg)";
  }
  return status_;
}

std::vector<TrajectoryPoint> hold_trajectory(const Eigen::VectorXd& q) {
  return {TrajectoryPoint{0.0, q, Eigen::VectorXd::Zero(q.size())}};
}

}  // namespace handeye::motion
