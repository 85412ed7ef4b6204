// The simulated arm under rostest: a move timed by the planner (timed_move) sent
// as trajectory_msgs/JointTrajectory to /arm_controller/command, watched from
// /joint_states by MoveMonitor, with robot_state_publisher's TF checked against
// the planner's forward kinematics. ~fault: none (arrives), stops_short (the arm
// stops at 80% of the move: no progress), stall (joint states stop). Every command
// is taken whole by the controller's rules (its ~command_outcomes).
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <sensor_msgs/JointState.h>
#include <std_msgs/String.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>
#include <trajectory_msgs/JointTrajectory.h>

#include <algorithm>
#include <fstream>
#include <sstream>

#include "handeye_covariance/motion/arm.h"
#include "handeye_covariance/motion/move_monitor.h"
#include "handeye_covariance/ros/msg_conversion.h"

using namespace handeye;

namespace {

motion::Arm load_arm() {
  std::ifstream in(ros::NodeHandle("~").param<std::string>("urdf_path", ""));
  std::stringstream text;
  text << in.rdbuf();
  return motion::Arm::from_urdf(text.str(), "base_link", "tool0", "~urdf_path");
}

}  // namespace

TEST(SimulatedArm, FollowsATimedMoveOrSaysWhyNot) {
  ros::NodeHandle node;
  const std::string fault = ros::NodeHandle("~").param<std::string>("fault", "none");
  const motion::Arm arm = load_arm();
  Eigen::VectorXd q;
  double last_state = 0.0;
  auto sub = node.subscribe<sensor_msgs::JointState>("joint_states", 10, [&](const sensor_msgs::JointStateConstPtr& m) {
    Eigen::VectorXd read(arm.joints());  // by name, in the chain's order
    for (int j = 0; j < arm.joints(); ++j) {
      const auto at = std::find(m->name.begin(), m->name.end(), arm.limits()[j].name);
      if (at == m->name.end()) return;
      read(j) = m->position.at(at - m->name.begin());
    }
    q = read;
    last_state = m->header.stamp.toSec();
  });
  std::vector<std::string> outcomes;  // the controller's verdict on each command
  auto outcome_sub = node.subscribe<std_msgs::String>(
      "arm_controller/command_outcomes", 10, [&](const std_msgs::StringConstPtr& m) { outcomes.push_back(m->data); });
  auto pub = node.advertise<trajectory_msgs::JointTrajectory>("arm_controller/command", 1, true);
  tf2_ros::Buffer buffer;
  tf2_ros::TransformListener listener(buffer);
  const ros::Time deadline = ros::Time::now() + ros::Duration(20.0);
  while (ros::ok() && (q.size() != 6 || pub.getNumSubscribers() == 0) && ros::Time::now() < deadline) {
    ros::spinOnce();
    ros::Duration(0.01).sleep();
  }
  ASSERT_EQ(q.size(), 6) << "no /joint_states from the simulated controller";

  Eigen::VectorXd goal = q;
  goal(0) += 0.4, goal(2) -= 0.3, goal(5) += 0.5;
  motion::MoveTiming timing;
  timing.speed_fraction = 0.5;
  const auto trajectory = motion::timed_move(arm, q, goal, timing);
  const double sent = ros::Time::now().toSec();
  motion::MoveMonitor monitor(trajectory, sent);
  pub.publish(conversions::to_msg(motion::move_command(arm, trajectory)));
  motion::MoveStatus status = motion::MoveStatus::Moving;
  double last_seen = -1.0;
  while (ros::ok() && status == motion::MoveStatus::Moving) {
    ros::spinOnce();
    if (last_state != last_seen) monitor.joint_state(last_state, q), last_seen = last_state;
    status = monitor.update(ros::Time::now().toSec());
    ros::Duration(0.005).sleep();
  }
  const double ended = ros::Time::now().toSec() - sent;
  std::printf("[ arm      ] fault %s: %s after %.2f s (move %.2f s)%s%s\n", fault.c_str(), motion::to_string(status),
              ended, trajectory.back().time, monitor.reason().empty() ? "" : ": ", monitor.reason().c_str());
  if (fault == "none") {
    ASSERT_EQ(status, motion::MoveStatus::Arrived);
    EXPECT_LT(ended, trajectory.back().time + 0.5);
    // robot_state_publisher's TF at the goal is the planner's forward kinematics.
    ros::Duration(0.3).sleep();
    ros::spinOnce();
    const auto tf = buffer.lookupTransform("base_link", "tool0", ros::Time(0), ros::Duration(2.0));
    const Eigen::Isometry3d T = conversions::to_eigen(tf.transform);
    EXPECT_LT((T.translation() - arm.forward(q).translation()).norm(), 1e-6);
    EXPECT_LT(Eigen::AngleAxisd(T.linear().transpose() * arm.forward(q).linear()).angle(), 1e-6);
    EXPECT_LT((T.translation() - arm.forward(goal).translation()).norm(), 0.005);
  } else if (fault == "stops_short") {
    ASSERT_EQ(status, motion::MoveStatus::Stalled);
    // The arm stops at 80% of the path, before the planned end: caught within stall_time of that.
    EXPECT_LT(ended, trajectory.back().time + motion::MoveLimits{}.stall_time) << monitor.reason();
  } else if (fault == "stall") {
    ASSERT_EQ(status, motion::MoveStatus::JointStatesStalled);
  }
  if (status != motion::MoveStatus::Arrived) pub.publish(conversions::to_msg(motion::hold_command(arm)));
  const ros::Time until = ros::Time::now() + ros::Duration(1.0);
  while (ros::ok() && outcomes.size() < (status == motion::MoveStatus::Arrived ? 1u : 2u) && ros::Time::now() < until) {
    ros::spinOnce();
    ros::Duration(0.01).sleep();
  }
  ASSERT_FALSE(outcomes.empty());
  EXPECT_EQ(outcomes.front(), "accepted") << "the move is taken whole";
  if (status != motion::MoveStatus::Arrived) {
    ASSERT_EQ(outcomes.size(), 2u);
    EXPECT_EQ(outcomes.back(), "hold");
  }
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_simulated_arm");
  ros::NodeHandle keep;
  return RUN_ALL_TESTS();
}
