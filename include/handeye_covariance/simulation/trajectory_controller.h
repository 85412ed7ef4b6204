// A position-controlled arm under ros_controllers' joint_trajectory_controller,
// simulated without ROS, for the simulated arm's node and the motion tests. It
// applies the controller's rules to each command (joint_trajectory_controller's
// updateTrajectoryCommand and initJointTrajectory, summarised in docs/motion.md):
//   - not running: every command is refused, the empty one too;
//   - no points: hold the current (actual) position, decelerating over
//     `stop_trajectory_duration` (its parameter; 0 by default: at once; with d,
//     the arm comes to rest 5/8 v d further, its quintic segment's midpoint);
//   - refused: times not strictly increasing, joints other than the controller's,
//     point sizes that do not match;
//   - a zero stamp starts the command at the next control update, a stamp in the
//     future at that time; points at or before that start are dropped (a first
//     point at time 0 with a zero stamp silently); all of them dropped: the
//     command is ignored and the running trajectory goes on;
//   - otherwise the running trajectory is kept up to the command's start and
//     bridged from its desired state there to the first point kept;
//   - between points: linear, cubic or quintic as positions, velocities and
//     accelerations are given; after the last point it holds it.
// Path and goal tolerances are not enforced (the topic interface has none).
// Speed scaling, as the UR driver's scaled_pos_joint_traj_controller: the
// trajectory's clock advances by speed_scale times each control period.
// Faults for the tests: the arm stops at a fraction of each move (a protective
// stop: the arm and the trajectory's clock stop, as a UR's driver scales it to 0).
// Not modelled: a continuous joint's wraparound in the bridge, and tracking lag (the
// arm is where the trajectory puts it, as ros_control's simulated position interface).
// Times are seconds on the caller's clock (the node's ROS time). SimulatedArm runs
// one on a simulated clock, and run_move makes a move through it as the calibration
// node does (ros/arm_mover.cpp), for the tests and studies without ROS.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "handeye_covariance/motion/move_monitor.h"
#include "handeye_covariance/motion/trajectory.h"

namespace handeye {

struct ControllerOptions {
  std::vector<std::string> joints;  // the controller's joints, in the order its state is reported
  double stop_trajectory_duration = 0.0;  // s, joint_trajectory_controller's parameter
  double speed_scale = 1.0;               // (0, 1]: the trajectory runs this much slower in time
  bool running = true;                    // false: a controller that was not started refuses every command
  double stop_fraction = 1.0;             // < 1: the arm stops once it has covered this fraction of a move
};

/// What the controller made of one command.
struct CommandOutcome {
  enum class Kind { Accepted, Hold, Dropped, Refused };
  Kind kind = Kind::Accepted;
  int points_dropped = 0;  // points before the start, beyond a first one at 0 with a zero stamp
  std::string message;     // the controller's own words for a drop or a refusal ("" when taken whole)
  /// Taken as sent: accepted with no point dropped, or a hold.
  bool taken_whole() const { return (kind == Kind::Accepted && points_dropped == 0) || kind == Kind::Hold; }
};
const char* to_string(CommandOutcome::Kind kind);  // "accepted", "hold", "dropped", "refused"

class SimulatedTrajectoryController {
 public:
  /// Holding `initial` (one value per options.joints) from `now`. Throws HandEyeError for sizes that differ.
  SimulatedTrajectoryController(ControllerOptions options, Eigen::VectorXd initial, double now);

  /// A command received at `now` (the controller takes it against its last control update).
  CommandOutcome command(const motion::TrajectoryCommand& command, double now);
  /// One control update at `now` (after the last one): the arm moves.
  void update(double now);

  void set_speed_scale(double scale);  // clamped to [0, 1]
  double speed_scale() const { return options_.speed_scale; }
  const Eigen::VectorXd& position() const { return position_; }  // the arm's, after the last update
  const Eigen::VectorXd& velocity() const { return velocity_; }
  /// Whether the trajectory is still moving the desired state at the last update.
  bool moving() const;
  const ControllerOptions& options() const { return options_; }

 private:
  void hold();
  std::vector<motion::SplineSegment>::const_iterator active(double uptime) const;
  motion::JointState desired(double uptime) const;

  ControllerOptions options_;
  Eigen::VectorXd position_, velocity_;
  double time_ = 0.0, period_ = 0.0, uptime_ = 0.0;  // the last update: its time, scaled period, trajectory clock
  std::vector<motion::SplineSegment> trajectory_;    // on the trajectory clock
  Eigen::VectorXd move_from_, move_goal_;            // the latest move, for stop_fraction
  bool stopped_short_ = false;
};

/// The controller on a simulated clock, its control loop and joint states every
/// `period`, with every command's outcome kept.
class SimulatedArm {
 public:
  /// options.joints empty: the arm's joints.
  SimulatedArm(const motion::Arm& arm, const Eigen::VectorXd& q, ControllerOptions options = {}, double now = 1000.0,
               double period = 0.01);
  const CommandOutcome& send(const motion::TrajectoryCommand& command);
  void tick();
  void run(double seconds);
  /// Ticks until the effector has moved less than `translation` (m) and `rotation` (rad) over the
  /// last `window` s (the sampler's stillness); false if not within `give_up` s.
  bool wait_still(const motion::Arm& arm, double window, double translation, double rotation, double give_up = 120.0);

  SimulatedTrajectoryController& controller() { return controller_; }
  const Eigen::VectorXd& q() const { return controller_.position(); }
  double now() const { return now_; }
  const std::vector<CommandOutcome>& outcomes() const { return outcomes_; }
  bool all_taken_whole() const;

 private:
  SimulatedTrajectoryController controller_;
  double now_, period_;
  std::vector<CommandOutcome> outcomes_;
};

/// One move as the calibration node makes it: the command, the monitor on each joint
/// state; on a failure the hold (an empty trajectory), then the arm watched to rest.
struct MoveRun {
  motion::MoveStatus status = motion::MoveStatus::Moving;
  std::string reason;
  double decided = 0.0;       // s after the command: arrived, or stopped
  double travel_after = 0.0;  // rad: the largest joint change from the hold to rest
};
struct MoveRunHooks {
  std::function<void(SimulatedArm&, const motion::MoveMonitor&)> during;  // after each joint state
  std::function<bool(double elapsed)> joint_states_heard;                 // none: always
};
MoveRun run_move(SimulatedArm& sim, const motion::Arm& arm, const std::vector<motion::TrajectoryPoint>& trajectory,
                 const motion::MoveLimits& limits = {}, const MoveRunHooks& hooks = {});

}  // namespace handeye
