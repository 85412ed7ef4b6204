// The robot moving itself, on the calibration node: the next move from
// the session (auto/auto_calibration.h), sent as trajectory_msgs/JointTrajectory
// to the trajectory controller's command topic, watched from /joint_states
// (motion/move_monitor.h), then a sample where the arm stands still.
//
// ~motion/mode confirm (default): the next move is planned and shown (RViz, ~motion_status)
// as soon as there is a sample and after each move, and the arm moves only on Move;
// auto: auto_calibrate at start. Services beside the node's others (/<namespace>/...):
// plan_move plans the next move again; move executes the shown one (planning first
// if there is none); auto_calibrate plans, moves and samples until
// the target object sigma or ~motion/max_views; the action auto_calibrate_action
// (AutoCalibrate.action) does the same for scripts, with feedback, and cancelling it
// stops the arm. stop_motion sends a hold trajectory from the service call
// itself (no queue in between) and ends either mode. Every failure stops the
// motion and says why on ~motion_status: no view passes (with the planner's
// counts per reason), the controller does not arrive, joint states stall; a goal
// without a detection is skipped and the next view planned.
//
// Threads: callbacks only store (joint states) or set a request; the motion
// thread plans and moves. The session is read through SessionAccess.
#pragma once

#include <actionlib/server/simple_action_server.h>
#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <sensor_msgs/JointState.h>
#include <std_msgs/String.h>
#include <std_srvs/Trigger.h>

#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

#include "handeye_covariance/auto/auto_calibration.h"
#include "handeye_covariance/motion/move_monitor.h"
#include "handeye_covariance/ros/messages.h"

namespace handeye {

/// What the mover needs of the node's session (each call takes the node's lock).
struct SessionAccess {
  const CalibrationSession* session = nullptr;             // settings and const computations only
  std::function<SessionSnapshot()> snapshot;
  std::function<std::size_t()> samples;                    // accepted samples so far
  std::function<SessionEvent(double now)> take_sample;     // manual sampling at now
  /// Whether the latest analysis is of the current samples, and, when it has an
  /// estimate, its progress against a target object sigma (m; target_progress).
  std::function<std::pair<bool, std::optional<TargetProgress>>(double target)> progress;
  /// The worker's analysis when it is of the current samples (its ranking is what the mover plans from).
  std::function<std::optional<Analysis>()> analysis;
  /// The view the arm is to move to next (none: no plan), for the node's ~status and next-pose markers.
  std::function<void(const std::optional<ScoredPose>&)> show_plan;
};

class ArmMover {
 public:
  /// Reads ~motion/* and robot_description; throws HandEyeError naming what is wrong.
  ArmMover(ros::NodeHandle node, ros::NodeHandle private_node, SessionAccess access);
  /// Holds the arm if a move is under way (stop_for_shutdown).
  ~ArmMover();
  /// Before ROS shuts down: a move under way is stopped with a hold, given time to
  /// leave; an arm at rest is not commanded.
  void stop_for_shutdown();

 private:
  enum class Request { None, Plan, Move, Auto };
  bool plan_service(std_srvs::Trigger::Request&, std_srvs::Trigger::Response&);
  bool move_service(std_srvs::Trigger::Request&, std_srvs::Trigger::Response&);
  bool auto_service(std_srvs::Trigger::Request&, std_srvs::Trigger::Response&);
  bool stop_service(std_srvs::Trigger::Request&, std_srvs::Trigger::Response&);
  /// Takes a request unless busy (mutex_ held): the reason when busy.
  std::optional<std::string> ask(Request request);
  void on_goal();
  void on_preempt();
  /// Sends the hold, from the calling thread; the motion thread stops.
  void stop_now(const std::string& why);
  void on_joint_states(const sensor_msgs::JointStateConstPtr& msg);
  void run();   // the motion thread: work(), and a hold if it throws
  void work();
  /// Whether request `id` still stands (not stopped, replaced, or shutting down).
  bool asked(std::uint64_t id) const;
  /// Plans the next move for request `id` (mutex_ not held); false with the reason on ~motion_status.
  bool plan(std::uint64_t id);
  /// Moves to the planned goal and takes the sample there, for request `id`; false
  /// when the motion stopped or another request came.
  bool execute(std::uint64_t id);
  /// Publishes a command; with `id`, only while that request stands (false: not sent).
  bool send(const motion::TrajectoryCommand& command, std::optional<std::uint64_t> id = std::nullopt);
  /// ~motion_status (and the action's feedback); with `id`, only while that request stands.
  void status(const std::string& state, const std::string& text, std::optional<std::uint64_t> id = std::nullopt);
  std::optional<Eigen::VectorXd> joints() const;

  SessionAccess access_;
  // The services, the action and joint states, on their own thread (spinner_); before the
  // handles that use it, which are destroyed first.
  ros::CallbackQueue queue_;
  std::unique_ptr<motion::Arm> arm_;
  std::unique_ptr<motion::CollisionModel> collision_;
  std::unique_ptr<AutoCalibration> automatic_;
  motion::MoveLimits limits_;
  double sample_timeout_ = 4.0;  // s after arrival
  int max_views_ = 30;
  double target_object_sigma_ = 1e-3;
  bool auto_start_ = false;  // ~motion/auto_start, or ~motion/mode auto
  bool confirm_ = true;      // ~motion/mode confirm: the next move is planned and shown ahead of Move

  /// The planned move in RViz (~planned_move_markers): the arm's collision shapes at
  /// the goal as a translucent ghost, the camera's frustum there (once X is
  /// estimated) and the predicted gain; cleared once the move is done.
  void publish_plan_markers(const std::optional<NextMove>& move);
  ros::Publisher command_pub_, status_pub_, markers_pub_;
  ros::Subscriber joint_states_;
  std::vector<ros::ServiceServer> services_;
  std::unique_ptr<actionlib::SimpleActionServer<AutoCalibrateAction>> action_;

  mutable std::mutex mutex_;
  std::mutex send_mutex_;  // one command at a time (send)
  bool commanding_ = false;  // a move was sent and has not arrived, failed or been stopped
  bool closing_ = false;     // stop_for_shutdown: no request is taken, no move is sent
  std::condition_variable wake_;
  Request request_ = Request::None;
  bool shutting_down_ = false;
  /// Moved on by every request and by a stop: work started for an older one stops.
  std::uint64_t request_id_ = 0;
  std::optional<NextMove> planned_;
  bool action_goal_ = false;          // the current Auto is the action's goal
  double goal_target_ = 0.0;          // m, of that goal
  int goal_max_views_ = 0;
  std::vector<Eigen::Isometry3d> failed_;  // goals without a detection
  Eigen::VectorXd joints_;
  double joints_stamp_ = 0.0;
  std::string state_ = "idle";
  std::unique_ptr<ros::AsyncSpinner> spinner_;  // queue_'s thread
  std::thread thread_;  // last
};

}  // namespace handeye
