#include "handeye_covariance/simulation/trajectory_controller.h"

#include <algorithm>
#include <cmath>

#include <deque>

#include <Eigen/Geometry>

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/motion/arm.h"

namespace handeye {

const char* to_string(CommandOutcome::Kind kind) {
  switch (kind) {
    case CommandOutcome::Kind::Accepted: return "accepted";
    case CommandOutcome::Kind::Hold: return "hold";
    case CommandOutcome::Kind::Dropped: return "dropped";
    case CommandOutcome::Kind::Refused: return "refused";
  }
  return "unknown";
}

SimulatedTrajectoryController::SimulatedTrajectoryController(ControllerOptions options, Eigen::VectorXd initial,
                                                             double now)
    : options_(std::move(options)), position_(std::move(initial)), time_(now) {
  if (position_.size() != static_cast<Eigen::Index>(options_.joints.size()))
    throw HandEyeError(ErrorCode::WrongLength,
                       std::to_string(position_.size()) + " initial positions for " +
                           std::to_string(options_.joints.size()) + " joints",
                       "initial_positions", "give one position per joint, in the joints' order");
  velocity_ = Eigen::VectorXd::Zero(position_.size());
  set_speed_scale(options_.speed_scale);
  hold();  // as the controller does when it starts
}

void SimulatedTrajectoryController::set_speed_scale(double scale) {
  options_.speed_scale = std::clamp(std::isfinite(scale) ? scale : 0.0, 0.0, 1.0);
}

void SimulatedTrajectoryController::hold() {
  // joint_trajectory_controller's setHoldPosition: from the arm's position and velocity
  // to rest in stop_trajectory_duration d, at the midpoint of its (quintic) segment from
  // (p, v) to (p, -v) over 2d: p + 5 v d / 8, at rest; from the last update's trajectory time.
  const double d = options_.stop_trajectory_duration;
  motion::TrajectoryPoint from{0.0, position_, velocity_, Eigen::VectorXd::Zero(position_.size())};
  motion::TrajectoryPoint to{d, position_ + velocity_ * (5.0 * d / 8.0), Eigen::VectorXd::Zero(position_.size()),
                             Eigen::VectorXd::Zero(position_.size())};
  trajectory_ = {motion::SplineSegment(uptime_, from, uptime_ + d, to)};
}

std::vector<motion::SplineSegment>::const_iterator SimulatedTrajectoryController::active(double uptime) const {
  // The last segment that has started by then, or the first one before any has.
  const auto it = std::upper_bound(trajectory_.begin(), trajectory_.end(), uptime,
                                   [](double t, const motion::SplineSegment& s) { return t < s.start(); });
  return it == trajectory_.begin() ? it : it - 1;
}

motion::JointState SimulatedTrajectoryController::desired(double uptime) const { return active(uptime)->sample(uptime); }

bool SimulatedTrajectoryController::moving() const { return uptime_ < trajectory_.back().end(); }

CommandOutcome SimulatedTrajectoryController::command(const motion::TrajectoryCommand& msg, double) {
  CommandOutcome outcome;
  auto refuse = [&](const std::string& why) {
    outcome.kind = CommandOutcome::Kind::Refused;
    outcome.message = why;
    return outcome;
  };
  if (!options_.running) return refuse("Can't accept new commands. Controller is not running.");
  // Against the next control update: its time, and the trajectory clock then.
  const double next_time = time_ + period_, next_uptime = uptime_ + period_;
  if (msg.points.empty()) {
    hold();
    outcome.kind = CommandOutcome::Kind::Hold;
    return outcome;
  }
  for (std::size_t k = 1; k < msg.points.size(); ++k)
    if (!(msg.points[k].time > msg.points[k - 1].time))
      return refuse("Trajectory message contains waypoints that are not strictly increasing in time.");
  const std::size_t n = options_.joints.size();
  std::vector<int> index(n, -1);
  if (msg.joint_names.size() != n) return refuse("Cannot create trajectory from message. It does not contain the expected joints.");
  for (std::size_t j = 0; j < n; ++j) {
    const auto at = std::find(msg.joint_names.begin(), msg.joint_names.end(), options_.joints[j]);
    if (at == msg.joint_names.end())
      return refuse("Cannot create trajectory from message. It does not contain the expected joints.");
    index[j] = static_cast<int>(at - msg.joint_names.begin());
  }
  for (const motion::TrajectoryPoint& p : msg.points) {
    const auto bad = [&](const Eigen::VectorXd& v, bool required) {
      return (required || v.size() != 0) && v.size() != static_cast<Eigen::Index>(n);
    };
    if (bad(p.position, true) || bad(p.velocity, false) || bad(p.acceleration, false))
      return refuse("Size mismatch in trajectory point position, velocity or acceleration data.");
  }
  const double start = msg.stamp == 0.0 ? next_time : msg.stamp;
  const double o_start = next_uptime + (start - next_time);  // the command's start on the trajectory clock
  // The first point after the next update; those at or before it are dropped.
  std::size_t first = 0;
  while (first < msg.points.size() && !(next_time < start + msg.points[first].time)) ++first;
  if (first == msg.points.size()) {
    outcome.kind = CommandOutcome::Kind::Dropped;
    outcome.points_dropped = static_cast<int>(msg.points.size());
    outcome.message = "Dropping all " + std::to_string(msg.points.size()) +
                      " trajectory point(s), as they occur before the current time. Last point is " +
                      number_text(next_time - (start + msg.points.back().time), 3) + "s in the past.";
    return outcome;  // the running trajectory goes on
  }
  const bool silent = first == 1 && msg.points.front().time == 0.0 && msg.stamp == 0.0;
  if (first > 0 && !silent) {
    outcome.points_dropped = static_cast<int>(first);
    outcome.message = "Dropping first " + std::to_string(first) + " trajectory point(s) out of " +
                      std::to_string(msg.points.size()) + ", as they occur before the current time.";
  }
  // In the controller's joint order.
  auto ordered = [&](const motion::TrajectoryPoint& p) {
    motion::TrajectoryPoint q{p.time, Eigen::VectorXd(n), {}, {}};
    if (p.velocity.size()) q.velocity.resize(n);
    if (p.acceleration.size()) q.acceleration.resize(n);
    for (std::size_t j = 0; j < n; ++j) {
      q.position(j) = p.position(index[j]);
      if (p.velocity.size()) q.velocity(j) = p.velocity(index[j]);
      if (p.acceleration.size()) q.acceleration(j) = p.acceleration(index[j]);
    }
    return q;
  };
  // Keep the running trajectory from the segment active now to the one active at the
  // command's start, then bridge from its desired state there to the first point kept.
  const double bridge_start = std::max(o_start, next_uptime);
  const motion::JointState there = desired(bridge_start);
  std::vector<motion::SplineSegment> result(active(next_uptime), active(bridge_start) + 1);
  motion::TrajectoryPoint from{0.0, there.position, there.velocity, there.acceleration};
  motion::TrajectoryPoint to = ordered(msg.points[first]);
  result.emplace_back(bridge_start, from, o_start + to.time, to);
  for (std::size_t k = first + 1; k < msg.points.size(); ++k) {
    motion::TrajectoryPoint a = ordered(msg.points[k - 1]), b = ordered(msg.points[k]);
    result.emplace_back(o_start + a.time, a, o_start + b.time, b);
  }
  trajectory_ = std::move(result);
  move_from_ = position_;
  move_goal_ = ordered(msg.points.back()).position;
  stopped_short_ = false;
  return outcome;
}

void SimulatedTrajectoryController::update(double now) {
  // A protective stop holds the trajectory's clock too (a UR's driver scales it to 0).
  const double period = stopped_short_ ? 0.0 : std::max(0.0, now - time_) * options_.speed_scale;
  time_ = now, period_ = period, uptime_ += period;
  if (stopped_short_) {
    velocity_.setZero();
    return;
  }
  const motion::JointState d = desired(uptime_);
  if (options_.stop_fraction < 1.0 && move_goal_.size()) {
    const double total = (move_goal_ - move_from_).cwiseAbs().maxCoeff();
    if ((d.position - move_from_).cwiseAbs().maxCoeff() > options_.stop_fraction * total) {
      stopped_short_ = true;  // a protective stop: the arm stays where it is
      velocity_.setZero();
      return;
    }
  }
  position_ = d.position, velocity_ = d.velocity;
}

namespace {
ControllerOptions with_joints(ControllerOptions options, const motion::Arm& arm) {
  if (options.joints.empty())
    for (const motion::JointLimit& limit : arm.limits()) options.joints.push_back(limit.name);
  return options;
}
}  // namespace

SimulatedArm::SimulatedArm(const motion::Arm& arm, const Eigen::VectorXd& q, ControllerOptions options, double now,
                           double period)
    : controller_(with_joints(std::move(options), arm), q, now), now_(now), period_(period) {}

const CommandOutcome& SimulatedArm::send(const motion::TrajectoryCommand& command) {
  outcomes_.push_back(controller_.command(command, now_));
  return outcomes_.back();
}

void SimulatedArm::tick() { controller_.update(now_ += period_); }

void SimulatedArm::run(double seconds) {
  for (const double until = now_ + seconds; now_ < until - 1e-9;) tick();
}

bool SimulatedArm::all_taken_whole() const {
  return std::all_of(outcomes_.begin(), outcomes_.end(), [](const CommandOutcome& o) { return o.taken_whole(); });
}

bool SimulatedArm::wait_still(const motion::Arm& arm, double window, double translation, double rotation,
                              double give_up) {
  std::deque<std::pair<double, Eigen::Isometry3d>> recent;
  for (const double until = now_ + give_up; now_ < until;) {
    tick();
    recent.emplace_back(now_, arm.forward(q()));
    while (recent.front().first < now_ - window) recent.pop_front();
    const Eigen::Isometry3d d = recent.front().second.inverse() * recent.back().second;
    if (now_ - recent.front().first >= window - 1.1 * period_ && d.translation().norm() < translation &&
        Eigen::AngleAxisd(d.linear()).angle() < rotation)
      return true;
  }
  return false;
}

MoveRun run_move(SimulatedArm& sim, const motion::Arm& arm, const std::vector<motion::TrajectoryPoint>& trajectory,
                 const motion::MoveLimits& limits, const MoveRunHooks& hooks) {
  const double start = sim.now();
  sim.send(motion::move_command(arm, trajectory));
  motion::MoveMonitor monitor(trajectory, start, limits);
  MoveRun run;
  while (run.status == motion::MoveStatus::Moving) {
    sim.tick();
    if (!hooks.joint_states_heard || hooks.joint_states_heard(sim.now() - start)) monitor.joint_state(sim.now(), sim.q());
    if (hooks.during) hooks.during(sim, monitor);
    run.status = monitor.update(sim.now());
  }
  run.decided = sim.now() - start;
  run.reason = monitor.reason();
  if (run.status != motion::MoveStatus::Arrived) {
    const Eigen::VectorXd at_stop = sim.q();
    sim.send(motion::hold_command(arm));
    sim.run(2.0);
    run.travel_after = motion::largest_joint_change(sim.q(), at_stop);
  }
  return run;
}

}  // namespace handeye
