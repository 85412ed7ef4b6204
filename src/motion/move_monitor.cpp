#include "handeye_covariance/motion/move_monitor.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/core/units.h"

namespace handeye::motion {

const char* to_string(MoveStatus status) {
  switch (status) {
    case MoveStatus::Moving: return "moving";
    case MoveStatus::Arrived: return "arrived";
    case MoveStatus::Stalled: return "stalled";
    case MoveStatus::LeftPath: return "left_path";
    case MoveStatus::TimedOut: return "timed_out";
    case MoveStatus::JointStatesStalled: return "joint_states_stalled";
  }
  return "unknown";
}

namespace {

std::string deg(double radians, int digits = 3) { return number_text(degrees(radians), digits) + " deg"; }

constexpr double kSettleWindow = 0.1;  // s of joint states the speed at the goal is judged over

}  // namespace

void check_limits(const MoveLimits& limits) {
  const bool positive = limits.arrival_tolerance > 0.0 && limits.settle_speed > 0.0 && limits.stall_time > 0.0 &&
                        limits.progress_step > 0.0 && limits.start_step >= limits.progress_step && limits.path_tolerance > 0.0 && limits.arrival_allowance >= 0.0 &&
                        limits.joint_states_timeout > 0.0;
  if (!positive || !(limits.min_speed_scale > 0.0 && limits.min_speed_scale <= 1.0))
    throw HandEyeError(ErrorCode::MalformedFile,
                       "a move limit out of range (min speed scale " + number_text(limits.min_speed_scale) +
                           ", stall time " + number_text(limits.stall_time) + " s, progress step " +
                           number_text(degrees(limits.progress_step)) + " deg (at most the start step, " +
                           number_text(degrees(limits.start_step)) + " deg), path tolerance " +
                           number_text(degrees(limits.path_tolerance)) + " deg, arrival timeout " +
                           number_text(limits.arrival_allowance) + " s, joint states timeout " +
                           number_text(limits.joint_states_timeout) + " s)",
                       "~motion/min_speed_scale, stall_time, progress_step_deg, path_tolerance_deg, arrival_timeout, "
                       "joint_states_timeout",
                       "give a min speed scale in (0, 1] and positive times and angles");
}

MoveMonitor::MoveMonitor(std::vector<TrajectoryPoint> trajectory, double start_time, const MoveLimits& limits)
    : trajectory_(std::move(trajectory)), start_time_(start_time), limits_(limits) {
  if (trajectory_.empty())
    throw HandEyeError(ErrorCode::NoData, "an empty trajectory", "MoveMonitor", "plan a move first (timed_move)");
  check_limits(limits_);
  position_ = trajectory_.front().position;
  mark_time_ = start_time_;
  arc_.push_back(0.0);
  for (std::size_t k = 1; k < trajectory_.size(); ++k)
    arc_.push_back(arc_.back() + (trajectory_[k].position - trajectory_[k - 1].position).norm());
  // The planned progress in time, as the controller interpolates between the points
  // (its spline), every 2 ms: near the ends of a move it is far from linear.
  planned_.emplace_back(trajectory_.front().time, 0.0);
  for (std::size_t k = 1; k < trajectory_.size(); ++k) {
    const TrajectoryPoint& a = trajectory_[k - 1];
    const TrajectoryPoint& b = trajectory_[k];
    const SplineSegment segment(a.time, a, b.time, b);
    const int steps = std::max(1, static_cast<int>(std::ceil((b.time - a.time) / 0.002)));
    Eigen::VectorXd last = a.position;
    for (int i = 1; i <= steps; ++i) {
      const double t = a.time + (b.time - a.time) * i / steps;
      const Eigen::VectorXd q = segment.sample(t).position;
      planned_.emplace_back(t, planned_.back().second + (q - last).norm());
      last = q;
    }
  }
  // Scaled to the polyline's length (the spline's own may differ a little off a straight path).
  const double spline_length = planned_.back().second;
  if (spline_length > 0.0)
    for (auto& [t, a] : planned_) a *= arc_.back() / spline_length;
}

double MoveMonitor::planned_time(double arc) const {
  if (arc <= 0.0) return planned_.front().first;
  const auto it = std::lower_bound(planned_.begin(), planned_.end(), arc,
                                   [](const std::pair<double, double>& p, double a) { return p.second < a; });
  if (it == planned_.end()) return planned_.back().first;
  if (it == planned_.begin() || it->second == (it - 1)->second) return it->first;
  const auto& [t1, a1] = *it;
  const auto& [t0, a0] = *(it - 1);
  return t0 + (t1 - t0) * (arc - a0) / (a1 - a0);
}

double MoveMonitor::deadline() const {
  return start_time_ + (trajectory_.back().time - trajectory_.front().time) / limits_.min_speed_scale +
         limits_.arrival_allowance;
}

double MoveMonitor::stall_window() const {
  // Twice the time the trajectory takes, at min_speed_scale, to the next step from the latest
  // progress, less start_step: a previous move's last creep may have put the arm that far ahead.
  const double step = started_ ? limits_.progress_step : limits_.start_step;
  const double next = std::min(mark_arc_ + step, arc_.back());
  const double from = std::max(0.0, mark_arc_ - limits_.start_step);
  return std::max(limits_.stall_time, 2.0 * (planned_time(next) - planned_time(from)) / limits_.min_speed_scale);
}

void MoveMonitor::joint_state(double t, const Eigen::VectorXd& q) {
  if (q.size() != position_.size() || !q.allFinite()) return;  // another chain's message, or no joint state
  position_ = q;
  const std::optional<double> previous = last_state_;
  last_state_ = t;
  recent_.emplace_back(t, q);
  while (recent_.size() > 2 && recent_[1].first <= t - kSettleWindow) recent_.pop_front();
  // Where on the path: the nearest point of the polyline through the trajectory's points.
  double best = std::numeric_limits<double>::infinity(), along = 0.0;
  for (std::size_t k = 0; k + 1 < trajectory_.size(); ++k) {
    const Eigen::VectorXd d = trajectory_[k + 1].position - trajectory_[k].position;
    const double length2 = d.squaredNorm();
    const double u = length2 > 0.0 ? std::clamp((q - trajectory_[k].position).dot(d) / length2, 0.0, 1.0) : 0.0;
    const double distance = (q - trajectory_[k].position - u * d).norm();
    if (distance < best) best = distance, along = arc_[k] + u * std::sqrt(length2);
  }
  if (trajectory_.size() == 1) best = (q - trajectory_.front().position).norm();
  covered_ = along, off_path_ = best;
  if (!previous || *previous < start_time_) mark_arc_ = covered_;  // the first joints of the move: its baseline
  if (covered_ >= mark_arc_ + (started_ ? limits_.progress_step : limits_.start_step)) {
    mark_arc_ = covered_, mark_time_ = t;
    started_ = true;
  }
}

MoveStatus MoveMonitor::update(double now) {
  if (status_ != MoveStatus::Moving) return status_;
  const Eigen::VectorXd& goal = trajectory_.back().position;
  const double off = (position_ - goal).cwiseAbs().maxCoeff();
  auto stop = [&](MoveStatus status, const std::string& why) {
    status_ = status;
    reason_ = why;
    return status_;
  };
  const double since = now - last_state_.value_or(start_time_);
  if (since > limits_.joint_states_timeout)
    return stop(MoveStatus::JointStatesStalled, "no joint states for " + number_text(since, 3) + " s (more than " +
                                                    number_text(limits_.joint_states_timeout, 2) + " s) during the move");
  // Arrived: at the goal and settled (the last 0.1 s of joint states).
  if (last_state_ && *last_state_ >= start_time_ && off <= limits_.arrival_tolerance && recent_.size() >= 2) {
    const double span = recent_.back().first - recent_.front().first;
    const double speed = span > 0.0 ? (recent_.back().second - recent_.front().second).cwiseAbs().maxCoeff() / span : 0.0;
    if (span >= 0.5 * kSettleWindow && speed <= limits_.settle_speed) {
      status_ = MoveStatus::Arrived;
      return status_;
    }
  }
  if (off_path_ > limits_.path_tolerance)
    return stop(MoveStatus::LeftPath, "the arm left the planned path: it is " + deg(off_path_) + " (joint space) from it (more than " +
                                          deg(limits_.path_tolerance) +
                                          "): another command or controller is moving it");
  const double window = stall_window();
  if (now - mark_time_ > window) {
    const std::string scale = number_text(100.0 * limits_.min_speed_scale, 3) + "% speed";
    if (!started_) {
      const double covers = (planned_time(std::min(mark_arc_ + limits_.start_step, arc_.back())) - planned_time(mark_arc_)) /
                            limits_.min_speed_scale;
      return stop(MoveStatus::Stalled,
                  "did not arrive: the arm did not start along the planned path within " + number_text(now - start_time_, 3) +
                      " s (it moved less than " + deg(limits_.start_step, 2) + "; the trajectory covers that in " +
                      number_text(covers, 2) + " s at " + scale +
                      "): is the controller running, and does it take this command?");
    }
    return stop(MoveStatus::Stalled, "did not arrive: no progress along the planned path for " +
                                         number_text(now - mark_time_, 3) + " s (less than " +
                                         deg(limits_.progress_step, 2) + "), a joint still " + deg(off) +
                                         " from the goal: the arm stopped or was stopped (a protective stop, "
                                         "an obstacle, the speed slider at 0)");
  }
  if (now > deadline())
    return stop(MoveStatus::TimedOut, "did not arrive within " + number_text(deadline() - start_time_, 3) +
                                          " s (its planned " +
                                          number_text(trajectory_.back().time - trajectory_.front().time, 3) + " s run at " +
                                          number_text(100.0 * limits_.min_speed_scale, 3) + "% speed, + " +
                                          number_text(limits_.arrival_allowance, 3) + " s): a joint is still " +
                                          deg(off) + " from the goal (tolerance " + deg(limits_.arrival_tolerance) + ")");
  return status_;
}

}  // namespace handeye::motion
