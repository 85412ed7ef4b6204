// A position-controlled arm under ros_controllers' joint_trajectory_controller,
// simulated without ROS for the simulated arm's node and the motion tests. Each command
// gets that controller's rules (docs/motion.md, "The simulated arm's controller"):
// refused, dropped, an empty one a hold, else bridged from the running trajectory;
// between points linear, cubic or quintic as positions, velocities and accelerations
// are given, the last one held. The trajectory clock runs at speed_scale (the UR
// driver's scaling); stop_fraction stops the arm and that clock part way (a protective
// stop). Times: s on the caller's clock. SimulatedArm runs one on a simulated clock;
// run_move makes a move through it as the calibration node does (ros/arm_mover.cpp).
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
