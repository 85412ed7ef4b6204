// A simulated arm's trajectory controller, for trying the robot moving itself
// without a robot and for the rostests. It takes what ros_control's
// joint_trajectory_controller takes on its `command` topic
// (trajectory_msgs/JointTrajectory, joints in any order, a zero stamp meaning
// "now", an empty trajectory meaning "hold here"), follows it (cubic between
// points with velocities, linear without), and publishes sensor_msgs/JointState
// on /joint_states at ~rate. robot_state_publisher turns those into TF.
//
// Faults for the tests: ~stop_fraction < 1 stops every move short at that
// fraction of its path (a controller that never arrives); ~stall_after > 0 stops
// publishing joint states that many seconds after the first command.
#include <ros/ros.h>
#include <sensor_msgs/JointState.h>
#include <trajectory_msgs/JointTrajectory.h>

#include <map>
#include <vector>

#include "handeye_covariance/ros/params.h"

namespace handeye {
namespace {

class SimulatedTrajectoryController {
 public:
  SimulatedTrajectoryController(ros::NodeHandle node, ros::NodeHandle pn) {
    joints_ = param(pn, "joints", std::vector<std::string>{"shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint",
                                                          "wrist_1_joint", "wrist_2_joint", "wrist_3_joint"});
    position_ = param(pn, "initial_positions", std::vector<double>{0.0, -M_PI / 2, M_PI / 2, -M_PI / 2, -M_PI / 2, 0.0});
    if (position_.size() != joints_.size()) {
      ROS_FATAL("~initial_positions has %zu values for %zu ~joints: give one per joint", position_.size(),
                joints_.size());
      ros::shutdown();
      return;
    }
    stop_fraction_ = param(pn, "stop_fraction", 1.0);
    stall_after_ = param(pn, "stall_after", 0.0);
    states_ = node.advertise<sensor_msgs::JointState>("joint_states", 10);
    command_ = pn.subscribe("command", 10, &SimulatedTrajectoryController::on_command, this);
    timer_ = node.createTimer(ros::Duration(1.0 / param(pn, "rate", 100.0)), &SimulatedTrajectoryController::tick, this);
  }

 private:
  struct Knot {
    double t;
    std::vector<double> q, v;  // v empty: linear
  };

  void on_command(const trajectory_msgs::JointTrajectory& msg) {
    const ros::Time now = ros::Time::now();
    if (first_command_.isZero()) first_command_ = now;
    if (msg.points.empty()) {  // hold where it is
      knots_.clear();
      return;
    }
    std::vector<int> index(joints_.size(), -1);
    for (std::size_t j = 0; j < joints_.size(); ++j)
      for (std::size_t k = 0; k < msg.joint_names.size(); ++k)
        if (msg.joint_names[k] == joints_[j]) index[j] = static_cast<int>(k);
    for (std::size_t j = 0; j < joints_.size(); ++j) {
      if (index[j] < 0) {
        ROS_ERROR("trajectory refused: it has no joint '%s' (this controller's joints: ~joints)", joints_[j].c_str());
        return;  // the previous trajectory goes on, as joint_trajectory_controller does
      }
    }
    for (const auto& point : msg.points) {
      if (point.positions.size() != msg.joint_names.size()) {
        ROS_ERROR("trajectory refused: a point has %zu positions for %zu joints", point.positions.size(),
                  msg.joint_names.size());
        return;
      }
    }
    knots_.clear();
    start_ = msg.header.stamp.isZero() ? now : msg.header.stamp;
    from_ = position_;
    knots_.push_back({0.0, position_, std::vector<double>(joints_.size(), 0.0)});
    for (const auto& point : msg.points) {
      Knot knot{point.time_from_start.toSec(), {}, {}};
      for (std::size_t j = 0; j < joints_.size(); ++j) {
        knot.q.push_back(point.positions[index[j]]);
        if (point.velocities.size() == msg.joint_names.size()) knot.v.push_back(point.velocities[index[j]]);
      }
      if (knot.t <= knots_.back().t) {
        if (knots_.size() == 1 && knot.t <= 0.0) knots_.clear();  // a point at 0: go there at once
        else continue;
      }
      knots_.push_back(knot);
    }
  }

  // Where the trajectory puts the joints at s seconds from its start.
  std::vector<double> sample(double s) const {
    if (s >= knots_.back().t) return knots_.back().q;
    std::size_t k = 1;
    while (knots_[k].t < s) ++k;
    const Knot& a = knots_[k - 1];
    const Knot& b = knots_[k];
    const double h = b.t - a.t, u = (s - a.t) / h;
    std::vector<double> q(joints_.size());
    for (std::size_t j = 0; j < q.size(); ++j) {
      if (a.v.empty() || b.v.empty()) {
        q[j] = a.q[j] + u * (b.q[j] - a.q[j]);
      } else {  // cubic Hermite
        const double h00 = 2 * u * u * u - 3 * u * u + 1, h10 = u * u * u - 2 * u * u + u;
        const double h01 = -2 * u * u * u + 3 * u * u, h11 = u * u * u - u * u;
        q[j] = h00 * a.q[j] + h10 * h * a.v[j] + h01 * b.q[j] + h11 * h * b.v[j];
      }
    }
    return q;
  }

  void tick(const ros::TimerEvent&) {
    const ros::Time now = ros::Time::now();
    if (!knots_.empty() && now >= start_) {
      const std::vector<double> target = sample((now - start_).toSec());
      // A faulty controller stops short: at stop_fraction of the way from where the move began.
      const std::vector<double>& goal = knots_.back().q;
      bool beyond = false;
      double travelled = 0.0, total = 0.0;
      for (std::size_t j = 0; j < target.size(); ++j) {
        travelled = std::max(travelled, std::abs(target[j] - from_[j]));
        total = std::max(total, std::abs(goal[j] - from_[j]));
      }
      beyond = stop_fraction_ < 1.0 && travelled > stop_fraction_ * total;
      if (!beyond) position_ = target;
    }
    if (stall_after_ > 0.0 && !first_command_.isZero() && (now - first_command_).toSec() > stall_after_) return;
    sensor_msgs::JointState state;
    state.header.stamp = now;
    state.name = joints_;
    state.position = position_;
    states_.publish(state);
  }

  std::vector<std::string> joints_;
  std::vector<double> position_, from_;
  std::vector<Knot> knots_;
  ros::Time start_, first_command_;
  double stop_fraction_ = 1.0, stall_after_ = 0.0;
  ros::Publisher states_;
  ros::Subscriber command_;
  ros::Timer timer_;
};

}  // namespace
}  // namespace handeye

int main(int argc, char** argv) {
  ros::init(argc, argv, "simulated_trajectory_controller");
  handeye::SimulatedTrajectoryController controller{ros::NodeHandle(), ros::NodeHandle("~")};
  ros::spin();
  return 0;
}
