// A simulated arm under ros_controllers' joint_trajectory_controller, for trying the
// robot moving itself without a robot and for the rostests. Its command topic takes
// trajectory_msgs/JointTrajectory by that controller's rules
// (simulation/trajectory_controller.h): a zero stamp is "now", points in the past
// are dropped, an empty trajectory holds. It publishes sensor_msgs/JointState on
// /joint_states at ~rate; robot_state_publisher turns those into TF.
//
// Parameters: ~joints, ~initial_positions, ~rate (Hz), ~stop_trajectory_duration
// (s, the controller's), ~speed_scale (the UR driver's speed slider, 0-1; the topic
// ~set_speed_scale (std_msgs/Float64) changes it during a move).
// Faults for the tests: ~stop_fraction < 1 stops the arm at that fraction of each
// move (a protective stop); ~stall_after > 0 silences /joint_states that many
// seconds after the first command, for ~stall_for seconds (0: for good);
// ~running false: a controller that was not started refuses every command.
// For the tests, beside /joint_states: ~actual_joint_states, the arm's joints
// whatever /joint_states does, and ~command_outcomes (std_msgs/String), what the
// controller made of each command: "accepted", "hold", or "dropped: ..." /
// "refused: ..." / "accepted, N point(s) dropped: ..." in the controller's words.
#include <ros/ros.h>
#include <sensor_msgs/JointState.h>
#include <std_msgs/Float64.h>
#include <std_msgs/String.h>
#include <trajectory_msgs/JointTrajectory.h>

#include <memory>
#include <vector>

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/ros/msg_conversion.h"
#include "handeye_covariance/ros/params.h"
#include "handeye_covariance/simulation/trajectory_controller.h"

namespace handeye {
namespace {

class SimulatedControllerNode {
 public:
  SimulatedControllerNode(ros::NodeHandle node, ros::NodeHandle pn) {
    ControllerOptions options;
    options.joints = param(pn, "joints", std::vector<std::string>{"shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint",
                                                                  "wrist_1_joint", "wrist_2_joint", "wrist_3_joint"});
    const std::vector<double> initial =
        param(pn, "initial_positions", std::vector<double>{0.0, -M_PI / 2, M_PI / 2, -M_PI / 2, -M_PI / 2, 0.0});
    options.stop_trajectory_duration = param(pn, "stop_trajectory_duration", 0.0);
    options.speed_scale = param(pn, "speed_scale", 1.0);
    options.running = param(pn, "running", true);
    options.stop_fraction = param(pn, "stop_fraction", 1.0);
    stall_after_ = param(pn, "stall_after", 0.0);
    stall_for_ = param(pn, "stall_for", 0.0);
    controller_ = std::make_unique<SimulatedTrajectoryController>(
        options, Eigen::Map<const Eigen::VectorXd>(initial.data(), initial.size()), ros::Time::now().toSec());
    states_ = node.advertise<sensor_msgs::JointState>("joint_states", 10);
    actual_ = pn.advertise<sensor_msgs::JointState>("actual_joint_states", 100);
    outcomes_ = pn.advertise<std_msgs::String>("command_outcomes", 100, true);
    command_ = pn.subscribe("command", 1, &SimulatedControllerNode::on_command, this);  // as the controller's
    scale_ = pn.subscribe("set_speed_scale", 10, &SimulatedControllerNode::on_scale, this);
    timer_ = node.createTimer(ros::Duration(1.0 / param(pn, "rate", 100.0)), &SimulatedControllerNode::tick, this);
  }

 private:
  void on_command(const trajectory_msgs::JointTrajectory& msg) {
    const ros::Time now = ros::Time::now();
    if (first_command_.isZero()) first_command_ = now;
    const CommandOutcome outcome = controller_->command(conversions::to_core(msg), now.toSec());
    std_msgs::String text;
    text.data = to_string(outcome.kind);
    if (outcome.kind == CommandOutcome::Kind::Accepted && outcome.points_dropped > 0)
      text.data += ", " + std::to_string(outcome.points_dropped) + " point(s) dropped";
    if (!outcome.message.empty()) text.data += ": " + outcome.message;
    if (outcome.kind == CommandOutcome::Kind::Refused) ROS_ERROR("%s", outcome.message.c_str());
    else if (!outcome.message.empty()) ROS_WARN("%s", outcome.message.c_str());
    outcomes_.publish(text);
  }

  void on_scale(const std_msgs::Float64& msg) { controller_->set_speed_scale(msg.data); }

  void tick(const ros::TimerEvent&) {
    const ros::Time now = ros::Time::now();
    controller_->update(now.toSec());
    sensor_msgs::JointState state;
    state.header.stamp = now;
    state.name = controller_->options().joints;
    const Eigen::VectorXd& q = controller_->position();
    const Eigen::VectorXd& v = controller_->velocity();
    state.position.assign(q.data(), q.data() + q.size());
    state.velocity.assign(v.data(), v.data() + v.size());
    actual_.publish(state);
    if (stall_after_ > 0.0 && !first_command_.isZero()) {
      const double since = (now - first_command_).toSec() - stall_after_;
      if (since > 0.0 && (stall_for_ <= 0.0 || since < stall_for_)) return;  // silent
    }
    states_.publish(state);
  }

  std::unique_ptr<SimulatedTrajectoryController> controller_;
  double stall_after_ = 0.0, stall_for_ = 0.0;
  ros::Time first_command_;
  ros::Publisher states_, actual_, outcomes_;
  ros::Subscriber command_, scale_;
  ros::Timer timer_;
};

}  // namespace
}  // namespace handeye

int main(int argc, char** argv) {
  ros::init(argc, argv, "simulated_trajectory_controller");
  ros::NodeHandle node, private_node("~");
  try {
    handeye::SimulatedControllerNode controller{node, private_node};
    ros::spin();
  } catch (const handeye::HandEyeError& e) {
    ROS_FATAL("simulated_trajectory_controller: %s", e.what());
    return 1;
  }
  return 0;
}
