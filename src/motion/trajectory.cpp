#include "handeye_covariance/motion/trajectory.h"

#include <algorithm>
#include <cmath>

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/motion/arm.h"

namespace handeye::motion {

double MoveTiming::acceleration(int j) const {
  if (j < static_cast<int>(joint_acceleration.size()) && joint_acceleration[j] > 0.0)
    return std::min(max_acceleration, joint_acceleration[j]);
  return max_acceleration;
}

void check_timing(const MoveTiming& timing) {
  if (!(timing.speed_fraction > 0.0 && timing.speed_fraction <= 1.0))
    throw HandEyeError(ErrorCode::MalformedFile, "the speed fraction " + number_text(timing.speed_fraction) + " is not in (0, 1]",
                       "~motion/speed_fraction", "give a fraction of the URDF's velocity limits, e.g. 0.1");
  if (!(timing.max_acceleration > 0.0) || !(timing.dt > 0.0))
    throw HandEyeError(ErrorCode::MalformedFile,
                       "the acceleration bound " + number_text(timing.max_acceleration) + " rad/s^2 or the step " +
                           number_text(timing.dt) + " s is not positive",
                       "~motion/max_acceleration_deg", "give a positive acceleration bound, e.g. 86 deg/s^2");
}

std::vector<TrajectoryPoint> timed_move(const Arm& arm, const Eigen::VectorXd& from, const Eigen::VectorXd& to,
                                        const MoveTiming& timing) {
  check_timing(timing);
  // s(tau) = 10 tau^3 - 15 tau^4 + 6 tau^5: ds/dtau peaks at 15/8 (tau = 1/2),
  // d2s/dtau2 at 10/sqrt(3) (tau = (3 - sqrt(3))/6).
  const double peak_speed = 1.875, peak_acceleration = 10.0 / std::sqrt(3.0);
  double duration = timing.dt;
  for (int j = 0; j < arm.joints(); ++j) {
    const double travel = std::abs(to(j) - from(j));
    duration = std::max(duration, peak_speed * travel / (timing.speed_fraction * arm.limits()[j].velocity));
    duration = std::max(duration, std::sqrt(peak_acceleration * travel / timing.acceleration(j)));
  }
  // Points every dt, the last at the duration: one closer than 1 ms to it is left out (a
  // controller refuses times that are not strictly increasing, once rounded to ros::Duration).
  int steps = std::max(1, static_cast<int>(std::ceil(duration / timing.dt - 1e-9)));
  if (steps > 1 && duration - (steps - 1) * timing.dt < 1e-3) --steps;
  std::vector<TrajectoryPoint> points;
  for (int k = 0; k <= steps; ++k) {
    const double t = k == steps ? duration : k * timing.dt, tau = t / duration;
    const double s = tau * tau * tau * (10.0 + tau * (-15.0 + 6.0 * tau));
    const double ds = 30.0 * tau * tau * (1.0 - tau) * (1.0 - tau) / duration;
    const double dds = 60.0 * tau * (1.0 - tau) * (1.0 - 2.0 * tau) / (duration * duration);
    points.push_back({t, from + s * (to - from), ds * (to - from), dds * (to - from)});
  }
  return points;
}

namespace {
std::vector<std::string> joint_names(const Arm& arm) {
  std::vector<std::string> names;
  for (const JointLimit& limit : arm.limits()) names.push_back(limit.name);
  return names;
}
}  // namespace

TrajectoryCommand move_command(const Arm& arm, const std::vector<TrajectoryPoint>& trajectory) {
  return {0.0, joint_names(arm), trajectory};
}

TrajectoryCommand hold_command(const Arm& arm) { return {0.0, joint_names(arm), {}}; }

SplineSegment::SplineSegment(double start, const TrajectoryPoint& from, double end, const TrajectoryPoint& to)
    : start_(start), end_(end) {
  const Eigen::Index n = from.position.size();
  coefficients_ = Eigen::MatrixXd::Zero(n, 6);
  const double T = end - start;
  const Eigen::VectorXd& p0 = from.position;
  const Eigen::VectorXd& p1 = to.position;
  coefficients_.col(0) = p0;
  if (T <= 0.0) {  // a segment of no length: at its end at once
    coefficients_.col(0) = p1;
    return;
  }
  const bool velocities = from.velocity.size() == n && to.velocity.size() == n;
  const bool accelerations = velocities && from.acceleration.size() == n && to.acceleration.size() == n;
  if (!velocities) {
    coefficients_.col(1) = (p1 - p0) / T;
  } else if (!accelerations) {
    const Eigen::VectorXd& v0 = from.velocity;
    const Eigen::VectorXd& v1 = to.velocity;
    coefficients_.col(1) = v0;
    coefficients_.col(2) = (3.0 * (p1 - p0) - (2.0 * v0 + v1) * T) / (T * T);
    coefficients_.col(3) = (2.0 * (p0 - p1) + (v0 + v1) * T) / (T * T * T);
  } else {
    const Eigen::VectorXd& v0 = from.velocity;
    const Eigen::VectorXd& v1 = to.velocity;
    const Eigen::VectorXd& a0 = from.acceleration;
    const Eigen::VectorXd& a1 = to.acceleration;
    const double T2 = T * T, T3 = T2 * T;
    coefficients_.col(1) = v0;
    coefficients_.col(2) = 0.5 * a0;
    coefficients_.col(3) = (20.0 * (p1 - p0) - (8.0 * v1 + 12.0 * v0) * T - (3.0 * a0 - a1) * T2) / (2.0 * T3);
    coefficients_.col(4) = (30.0 * (p0 - p1) + (14.0 * v1 + 16.0 * v0) * T + (3.0 * a0 - 2.0 * a1) * T2) / (2.0 * T3 * T);
    coefficients_.col(5) = (12.0 * (p1 - p0) - 6.0 * (v1 + v0) * T - (a0 - a1) * T2) / (2.0 * T3 * T2);
  }
}

JointState SplineSegment::sample(double t) const {
  const Eigen::Index n = coefficients_.rows();
  JointState state{Eigen::VectorXd::Zero(n), Eigen::VectorXd::Zero(n), Eigen::VectorXd::Zero(n)};
  const bool after = t >= end_;
  const double s = std::clamp(t, start_, end_) - start_;
  for (int k = 5; k >= 0; --k) state.position = state.position * s + coefficients_.col(k);
  if (after) return state;  // at rest at the end
  for (int k = 5; k >= 1; --k) state.velocity = state.velocity * s + k * coefficients_.col(k);
  for (int k = 5; k >= 2; --k) state.acceleration = state.acceleration * s + k * (k - 1) * coefficients_.col(k);
  return state;
}

}  // namespace handeye::motion
