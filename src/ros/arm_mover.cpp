#include "handeye_covariance/ros/arm_mover.h"

#include <trajectory_msgs/JointTrajectory.h>

#include <algorithm>
#include <visualization_msgs/MarkerArray.h>

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/core/units.h"
#include "handeye_covariance/ros/covariance_markers.h"
#include "handeye_covariance/ros/msg_conversion.h"
#include "handeye_covariance/ros/params.h"

namespace handeye {
namespace {

double deg(const ros::NodeHandle& pn, const std::string& name, double fallback_deg) {
  return radians(param(pn, name, fallback_deg));
}

std::string mm(double m) { return number_text(millimetres(m), 3) + " mm"; }

}  // namespace

ArmMover::ArmMover(ros::NodeHandle node, ros::NodeHandle pn, SessionAccess access) : access_(std::move(access)) {
  std::string urdf, key;
  if (!node.searchParam("robot_description", key) || !node.getParam(key, urdf) || urdf.empty())
    throw HandEyeError(ErrorCode::MissingKey, "no URDF on the parameter robot_description", "~motion/enabled",
                       "load the robot's URDF (robot_state_publisher's launch does), or set ~motion/enabled false");
  const Rig& rig = access_.session->settings().rig;
  arm_ = std::make_unique<motion::Arm>(motion::Arm::from_urdf(urdf, rig.frames.base, rig.frames.effector, "robot_description"));
  const std::string obstacles_file = param<std::string>(pn, "motion/obstacles_file", "");
  motion::CollisionOptions collision;
  collision.padding = param(pn, "motion/padding", collision.padding);
  collision_ = std::make_unique<motion::CollisionModel>(
      *arm_, obstacles_file.empty() ? motion::table_plane() : motion::read_obstacles(obstacles_file), collision);

  AutoCalibrationOptions options;
  options.timing.speed_fraction = param(pn, "motion/speed_fraction", options.timing.speed_fraction);
  options.timing.max_acceleration = deg(pn, "motion/max_acceleration_deg", degrees(options.timing.max_acceleration));
  // MoveIt's joint limits where they are loaded (robot_description_planning/joint_limits/<joint>/max_acceleration).
  for (const motion::JointLimit& joint : arm_->limits()) {
    const std::string limits = "robot_description_planning/joint_limits/" + joint.name + "/";
    double a = 0.0;
    options.timing.joint_acceleration.push_back(
        param(node, limits + "has_acceleration_limits", false) && node.getParam(limits + "max_acceleration", a) ? a : 0.0);
  }
  options.planner.joint_margin = deg(pn, "motion/joint_margin_deg", 5.0);
  options.planner.max_joint_step = deg(pn, "motion/max_joint_step_deg", 90.0);
  const std::vector<double> box = param(pn, "motion/workspace", std::vector<double>{-1.0, -1.0, 0.05, 1.0, 1.0, 1.2});
  if (box.size() != 6)
    throw HandEyeError(ErrorCode::WrongLength, "~motion/workspace needs 6 numbers", "~motion/workspace",
                       "give [min x, min y, min z, max x, max y, max z] in the base frame, metres");
  options.planner.workspace = Eigen::AlignedBox3d(Eigen::Vector3d(box[0], box[1], box[2]), Eigen::Vector3d(box[3], box[4], box[5]));
  const std::vector<double> fov = param(pn, "motion/field_of_view_deg", std::vector<double>{60.0, 45.0});
  options.planner.field_of_view_x = radians(fov.at(0));
  options.planner.field_of_view_y = radians(fov.at(1));
  automatic_ = std::make_unique<AutoCalibration>(*collision_, std::nullopt, options);
  limits_.arrival_allowance = param(pn, "motion/arrival_timeout", limits_.arrival_allowance);
  limits_.stall_time = param(pn, "motion/stall_time", limits_.stall_time);
  limits_.min_speed_scale = param(pn, "motion/min_speed_scale", limits_.min_speed_scale);
  limits_.path_tolerance = deg(pn, "motion/path_tolerance_deg", degrees(limits_.path_tolerance));
  limits_.progress_step = deg(pn, "motion/progress_step_deg", degrees(limits_.progress_step));
  limits_.joint_states_timeout = param(pn, "motion/joint_states_timeout", limits_.joint_states_timeout);
  motion::check_limits(limits_);
  motion::check_timing(options.timing);
  sample_timeout_ = param(pn, "motion/sample_timeout", access_.session->settings().sampler.still_window + 3.0);
  max_views_ = param(pn, "motion/max_views", max_views_);
  auto_start_ = param(pn, "motion/auto_start", false);
  const std::string mode = param<std::string>(pn, "motion/mode", "confirm");
  if (mode != "confirm" && mode != "auto")
    throw HandEyeError(ErrorCode::MalformedFile, "unknown ~motion/mode '" + mode + "'", "~motion/mode",
                       "use confirm (the next move is planned and shown; Move moves) or auto (auto_calibrate at start)");
  confirm_ = mode == "confirm";
  auto_start_ = auto_start_ || mode == "auto";
  target_object_sigma_ = access_.session->settings().target_object_sigma;

  // Stop, the action and joint states on their own queue and thread: the node's slow services
  // (suggest_pose, check_calibration) on its two threads cannot delay them.
  node.setCallbackQueue(&queue_);
  command_pub_ = node.advertise<trajectory_msgs::JointTrajectory>(
      param<std::string>(pn, "motion/controller_topic", "/arm_controller/command"), 1);
  status_pub_ = pn.advertise<std_msgs::String>("motion_status", 10, true);
  markers_pub_ = pn.advertise<visualization_msgs::MarkerArray>("planned_move_markers", 1, true);
  joint_states_ = node.subscribe(param<std::string>(pn, "motion/joint_states_topic", "/joint_states"), 10,
                                 &ArmMover::on_joint_states, this);
  // Beside the node's other services (/<namespace>/calibrate, ...).
  services_ = {node.advertiseService("plan_move", &ArmMover::plan_service, this),
               node.advertiseService("move", &ArmMover::move_service, this),
               node.advertiseService("auto_calibrate", &ArmMover::auto_service, this),
               node.advertiseService("stop_motion", &ArmMover::stop_service, this)};
  action_ = std::make_unique<actionlib::SimpleActionServer<AutoCalibrateAction>>(node, "auto_calibrate_action", false);
  action_->registerGoalCallback([this] { on_goal(); });
  action_->registerPreemptCallback([this] { on_preempt(); });
  action_->start();
  status("idle", "the arm " + rig.frames.base + " -> " + rig.frames.effector + " (" + std::to_string(arm_->joints()) +
                     " joints), " + std::to_string(collision_->obstacles().size()) + " obstacle(s)");
  spinner_ = std::make_unique<ros::AsyncSpinner>(1, &queue_);
  spinner_->start();
  thread_ = std::thread(&ArmMover::run, this);
}

ArmMover::~ArmMover() {
  if (ros::ok()) stop_for_shutdown();
  if (spinner_) spinner_->stop();
  if (action_) action_->shutdown();
  {
    std::lock_guard<std::mutex> lock(mutex_);
    shutting_down_ = true;
    ++request_id_;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void ArmMover::on_joint_states(const sensor_msgs::JointStateConstPtr& msg) {
  Eigen::VectorXd q(arm_->joints());
  for (int j = 0; j < arm_->joints(); ++j) {
    const auto at = std::find(msg->name.begin(), msg->name.end(), arm_->limits()[j].name);
    if (at == msg->name.end() || static_cast<std::size_t>(at - msg->name.begin()) >= msg->position.size()) return;
    q(j) = msg->position[at - msg->name.begin()];
  }
  if (!q.allFinite()) return;  // a driver's NaN is no joint state
  std::lock_guard<std::mutex> lock(mutex_);
  joints_ = q;
  // When it came, on this node's clock (the monitor's timeouts): a driver's stamps may be on another host's.
  joints_stamp_ = ros::Time::now().toSec();
}

std::optional<Eigen::VectorXd> ArmMover::joints() const {
  std::lock_guard<std::mutex> lock(mutex_);
  if (joints_.size() == 0) return std::nullopt;
  return joints_;
}

void ArmMover::status(const std::string& state, const std::string& text, std::optional<std::uint64_t> id) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (id && request_id_ != *id) return;  // stopped or replaced meanwhile: its "stopped" stands
    state_ = state;
  }
  std_msgs::String msg;
  msg.data = state + ": " + text;
  status_pub_.publish(msg);
  bool goal;
  double goal_target;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    goal = action_goal_, goal_target = goal_target_;
  }
  if (goal && action_ && action_->isActive()) {
    AutoCalibrateFeedback feedback;
    feedback.samples = static_cast<int>(access_.samples());
    const auto progress = access_.progress(goal_target).second;
    feedback.object_error_mm = progress ? millimetres(progress->object_sigma) : 0.0;
    feedback.state = state;
    feedback.text = msg.data;
    action_->publishFeedback(feedback);
  }
  if (state == "failed")
    ROS_WARN("motion %s", msg.data.c_str());
  else
    ROS_INFO("motion %s", msg.data.c_str());
}

bool ArmMover::send(const motion::TrajectoryCommand& command, std::optional<std::uint64_t> id) {
  // One at a time, and a move only while its request stands: a stop in between
  // either follows the move (and holds it) or comes first (and the move is not sent).
  std::lock_guard<std::mutex> sending(send_mutex_);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!command.points.empty() && (closing_ || (id && request_id_ != *id))) return false;
    commanding_ = !command.points.empty();
  }
  command_pub_.publish(conversions::to_msg(command));
  return true;
}

std::optional<std::string> ArmMover::ask(Request request) {  // mutex_ held
  if (closing_) return std::string("the node is shutting down");
  // A plan only shows a move: anything asked for replaces it (confirm mode plans at start).
  if ((request_ != Request::None && request_ != Request::Plan) || state_ == "moving")
    return "busy (" + state_ + "): call ~stop_motion first";
  request_ = request, ++request_id_;
  if (request == Request::Auto) action_goal_ = false;  // the services' Auto; on_goal marks the action's
  wake_.notify_all();
  return std::nullopt;
}

bool ArmMover::plan_service(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  const std::optional<std::string> busy = ask(Request::Plan);
  res.success = !busy;
  res.message = busy ? *busy : "planning; the plan is on ~motion_status";
  return true;
}

bool ArmMover::move_service(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  const bool planned = planned_.has_value();
  const std::optional<std::string> busy = ask(Request::Move);
  res.success = !busy;
  res.message = busy ? *busy : planned ? "moving to the planned view" : "planning, then moving";
  return true;
}

bool ArmMover::auto_service(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  const std::optional<std::string> busy = ask(Request::Auto);
  res.success = !busy;
  res.message = busy ? *busy
                     : "calibrating by itself until " + mm(target_object_sigma_) + " or " + std::to_string(max_views_) +
                           " views; ~stop_motion stops it";
  return true;
}

bool ArmMover::stop_service(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
  stop_now("~stop_motion");
  if (action_->isActive()) {
    AutoCalibrateResult result;
    result.message = "stopped by ~stop_motion";
    action_->setAborted(result, result.message);
  }
  res.success = true;
  res.message = "stopped";
  return true;
}

void ArmMover::stop_now(const std::string& why) {
  // The hold goes out from here, not through the motion thread.
  {
    std::lock_guard<std::mutex> lock(mutex_);
    ++request_id_;  // whatever runs sees it is no longer asked for
    request_ = Request::None;
    action_goal_ = false;
    planned_.reset();
  }
  wake_.notify_all();
  send(motion::hold_command(*arm_));
  status("stopped", "the controller was told to hold where the arm is (an empty trajectory) (" + why + ")");
  publish_plan_markers(std::nullopt);
  access_.show_plan(std::nullopt);
}

void ArmMover::stop_for_shutdown() {
  bool moving;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    closing_ = true;  // no request is taken and no move is sent from now on
    ++request_id_;
    request_ = Request::None;
    moving = commanding_;
  }
  wake_.notify_all();
  if (!moving) return;  // an arm at rest is left alone: something else may be moving it by now
  stop_now("the node is shutting down");
  ros::WallDuration(0.2).sleep();  // for the hold to leave before the connections close
}

bool ArmMover::asked(std::uint64_t id) const {
  std::lock_guard<std::mutex> lock(mutex_);
  return request_id_ == id && !shutting_down_ && !closing_;
}

void ArmMover::on_goal() {
  const auto goal = action_->acceptNewGoal();
  std::lock_guard<std::mutex> lock(mutex_);
  if (const std::optional<std::string> busy = ask(Request::Auto)) {
    AutoCalibrateResult result;
    result.message = *busy;
    action_->setAborted(result, result.message);
    return;
  }
  action_goal_ = true;
  goal_target_ = goal->target_mm > 0.0 ? metres(goal->target_mm) : target_object_sigma_;
  goal_max_views_ = goal->max_views > 0 ? goal->max_views : max_views_;
}

void ArmMover::on_preempt() {
  stop_now("the action was cancelled");
  AutoCalibrateResult result;
  result.samples = static_cast<int>(access_.samples());
  result.message = "cancelled: the arm holds";
  action_->setPreempted(result, result.message);
}

void ArmMover::publish_plan_markers(const std::optional<NextMove>& move) {
  const Rig& rig = access_.session->settings().rig;
  const ros::Time stamp = ros::Time::now();
  visualization_msgs::MarkerArray markers;
  visualization_msgs::Marker clear;
  clear.header.frame_id = rig.frames.base;
  clear.header.stamp = stamp;
  clear.ns = "handeye_planned_move";
  clear.action = visualization_msgs::Marker::DELETEALL;
  markers.markers.push_back(clear);
  if (move) {
    const std::vector<Eigen::Isometry3d> poses = arm_->body_poses(move->plan.goal);
    int id = 0;
    for (std::size_t b = 0; b < arm_->bodies().size(); ++b) {
      for (const motion::Shape& shape : arm_->bodies()[b].shapes) {
        visualization_msgs::Marker m;
        m.header = clear.header;
        m.ns = clear.ns;
        m.id = id++;
        m.action = visualization_msgs::Marker::ADD;
        m.pose = conversions::to_pose_msg(poses[b] * shape.T_link_shape);
        if (shape.kind == motion::Shape::Kind::Box) {
          m.type = visualization_msgs::Marker::CUBE;
          m.scale.x = shape.size.x(), m.scale.y = shape.size.y(), m.scale.z = shape.size.z();
        } else if (shape.kind == motion::Shape::Kind::Cylinder) {
          m.type = visualization_msgs::Marker::CYLINDER;
          m.scale.x = m.scale.y = 2.0 * shape.size(0), m.scale.z = shape.size(1);
        } else {
          m.type = visualization_msgs::Marker::SPHERE;
          m.scale.x = m.scale.y = m.scale.z = 2.0 * shape.size(0);
        }
        m.color.r = 0.4f, m.color.g = 0.7f, m.color.b = 1.0f, m.color.a = 0.35f;
        markers.markers.push_back(m);
      }
    }
    const std::string label = move->bootstrap ? "planned: a first move"
                                              : "planned: object " + number_text(millimetres(move->object_sigma), 3) + " -> " +
                                                    number_text(millimetres(move->predicted_object_sigma), 3) + " mm (1 sigma)";
    NextPoseMarkerOptions options;
    options.ns = "handeye_planned_move_view";
    const visualization_msgs::MarkerArray view =
        next_pose_markers(rig, arm_->forward(move->plan.goal), move->X.value_or(Eigen::Isometry3d::Identity()), 0.3,
                          label, rig.frames.base, stamp, options);
    for (const auto& m : view.markers)  // without X, no frustum (id 1): the ghost effector frame and the label
      if (move->X || m.id != 1) markers.markers.push_back(m);
  }
  markers_pub_.publish(markers);
}

bool ArmMover::plan(std::uint64_t id) {
  const std::optional<Eigen::VectorXd> q = joints();
  if (!q) {
    status("failed", "no joint states of the arm's joints on " + joint_states_.getTopic(), id);
    return false;
  }
  const SessionSnapshot snapshot = access_.snapshot();
  const std::optional<Analysis> analysis = access_.analysis();
  const NextMove move = automatic_->next(*access_.session, snapshot, *q, failed_, analysis ? &*analysis : nullptr);
  if (!move.found) {
    access_.show_plan(std::nullopt);
    status("failed", move.reason, id);
    return false;
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (request_id_ != id) return false;  // stopped while planning: nothing is shown
    planned_ = move;
  }
  publish_plan_markers(move);
  std::optional<ScoredPose> view;
  if (!move.bootstrap) {
    view.emplace();
    view->T_base_effector = move.view.T_base_effector;
    view->T_camera_pattern = move.view.T_camera_pattern;
    view->object_sigma = move.predicted_object_sigma;
  }
  access_.show_plan(view);
  status("planned", (move.bootstrap ? "a first move (" : "view " + std::to_string(move.plan.chosen + 1) + " of the ranking (") +
                        move.plan.summary() + "), " + number_text(move.trajectory.back().time, 3) + " s" +
                        (move.bootstrap ? ""
                                        : ", object sigma " + mm(move.object_sigma) + " -> " +
                                              mm(move.predicted_object_sigma)),
         id);
  return true;
}

bool ArmMover::execute(std::uint64_t id) {
  std::optional<NextMove> move;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    move = planned_;
  }
  const std::optional<Eigen::VectorXd> now_joints = joints();
  // A plan from elsewhere (the arm moved since): plan again from here.
  if (!move || !now_joints || motion::largest_joint_change(*now_joints, move->plan.start) > 0.01) {
    if (!plan(id)) return false;
    std::lock_guard<std::mutex> lock(mutex_);
    move = planned_;
  }
  const std::size_t samples_before = access_.samples();
  const double start = ros::Time::now().toSec();
  motion::MoveMonitor monitor(move->trajectory, start, limits_);  // before the move goes out
  if (!send(motion::move_command(*arm_, move->trajectory), id)) return false;  // stopped meanwhile
  status("moving", number_text(move->trajectory.back().time, 3) + " s to the goal at full speed", id);
  double seen = -1.0;
  for (ros::Rate rate(200.0);; rate.sleep()) {
    if (!ros::ok()) {  // ROS went down under the move: try to hold it
      send(motion::hold_command(*arm_));
      return false;
    }
    Eigen::VectorXd q;
    double stamp;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (request_id_ != id) return false;  // stopped (the hold went out) or asked for something else
      q = joints_, stamp = joints_stamp_;
    }
    if (stamp != seen && q.size()) monitor.joint_state(stamp, q), seen = stamp;
    const motion::MoveStatus s = monitor.update(ros::Time::now().toSec());
    if (s == motion::MoveStatus::Arrived) break;
    if (s != motion::MoveStatus::Moving) {
      send(motion::hold_command(*arm_));
      status("failed", monitor.reason() + "; the controller was told to hold (an empty trajectory)", id);
      return false;
    }
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    planned_.reset();
    commanding_ = false;
  }
  publish_plan_markers(std::nullopt);
  access_.show_plan(std::nullopt);
  // The sample at the goal: the session's sampler takes it once the arm and the
  // detection are still; without auto-sampling, ask for it.
  status("sampling", "arrived; waiting for a still detection", id);
  const double arrived = ros::Time::now().toSec();
  const bool auto_sample = access_.session->settings().sampler.auto_sample;
  const double still = access_.session->settings().sampler.still_window;
  for (ros::Rate rate(20.0); ros::ok(); rate.sleep()) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (request_id_ != id) return false;
    }
    if (access_.samples() > samples_before) {
      status("sampled", "a sample at the goal (" + std::to_string(access_.samples()) + " in the session)", id);
      return true;
    }
    const double waited = ros::Time::now().toSec() - arrived;
    if (!auto_sample && waited > still + 0.1) access_.take_sample(ros::Time::now().toSec());
    if (waited > sample_timeout_) break;
  }
  failed_.push_back(arm_->forward(move->plan.goal));
  status("skipped", "no sample at the goal within " + number_text(sample_timeout_, 3) +
                        " s (is the target detected there, and TF " + access_.session->settings().rig.frames.base +
                        " -> " + access_.session->settings().rig.frames.effector +
                        " available?); the next view is planned without it",
         id);
  return true;
}

void ArmMover::run() {
  try {
    work();
  } catch (const std::exception& e) {  // a bug: the arm is held, and the motion says so
    send(motion::hold_command(*arm_));
    status("failed", std::string("internal error in the motion thread: ") + e.what() +
                         "; the controller was told to hold (an empty trajectory)");
    ROS_ERROR("motion thread: %s", e.what());
  }
}

void ArmMover::work() {
  // Wait for the arm's joints and a first sample; then auto: calibrate by itself;
  // confirm: plan the next move and show it (Move moves).
  while (auto_start_ || confirm_) {
    const bool sampled = access_.samples() > 0;  // the node's lock, not this one's
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (shutting_down_ || closing_) return;
      if (request_ != Request::None) break;  // asked for something meanwhile
      if (joints_.size() && sampled) {
        if (auto_start_) request_ = Request::Auto, ++request_id_;
        else request_ = Request::Plan, ++request_id_;
        break;
      }
    }
    ros::Duration(0.1).sleep();
  }
  while (true) {
    Request request;
    std::uint64_t id;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [&] { return shutting_down_ || request_ != Request::None; });
      if (shutting_down_) return;
      request = request_, id = request_id_;
    }
    if (request == Request::Plan) {
      plan(id);
    } else if (request == Request::Move) {
      if (execute(id) && confirm_) plan(id);  // the next one, shown for the operator's Move
    } else if (request == Request::Auto) {
      double target = target_object_sigma_;
      int max_views = max_views_;
      {
        std::lock_guard<std::mutex> lock(mutex_);
        if (action_goal_) target = goal_target_, max_views = goal_max_views_;
      }
      bool reached = false;
      for (int views = 0;; ++views) {
        if (!asked(id)) break;
        // A fresh estimate of every sample so far (the node's worker follows each sample).
        auto [fresh, progress] = access_.progress(target);
        for (int wait = 0; wait < 200 && !fresh && asked(id); ++wait) {
          ros::Duration(0.05).sleep();
          std::tie(fresh, progress) = access_.progress(target);
        }
        if (!asked(id)) break;  // stopped, or the node is going
        if (progress && progress->reached) {
          reached = true;
          status("done", "object sigma " + mm(progress->object_sigma) + " <= " + mm(target) + " after " +
                             std::to_string(access_.samples()) + " samples", id);
          break;
        }
        if (views >= max_views) {
          status("failed", std::to_string(max_views) + " moves (the most allowed) without reaching " + mm(target), id);
          break;
        }
        if (!plan(id) || !execute(id)) break;
      }
      bool goal;
      std::string last;
      {
        std::lock_guard<std::mutex> lock(mutex_);
        goal = action_goal_ && request_id_ == id;  // not stopped, cancelled or replaced meanwhile
        if (goal) action_goal_ = false;
        last = state_;
      }
      if (goal && action_->isActive()) {
        AutoCalibrateResult result;
        result.reached = reached;
        result.samples = static_cast<int>(access_.samples());
        const auto last_progress = access_.progress(target).second;
        result.object_error_mm = last_progress ? millimetres(last_progress->object_sigma) : 0.0;
        result.message = last;
        if (reached)
          action_->setSucceeded(result, "reached");
        else
          action_->setAborted(result, "not reached: see ~motion_status");
      }
    }
    std::lock_guard<std::mutex> lock(mutex_);
    if (request_id_ == id) request_ = Request::None;  // a request made meanwhile runs next
  }
}

}  // namespace handeye
