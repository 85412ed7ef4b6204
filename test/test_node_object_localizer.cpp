// Client for object_localizer.test: plays the robot's TF, the calibration node's
// latched ~calibration and object detections; checks T_base_object and refusals.
#include <std_msgs/String.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_broadcaster.h>
#include <tf2_ros/transform_listener.h>

#include "handeye_covariance/core/object_pose.h"
#include "handeye_covariance/simulation/simulation.h"
#include "handeye_covariance/ros/msg_conversion.h"
#include "node_test_helpers.h"

namespace handeye {
namespace {

using geometry_msgs::PoseWithCovarianceStamped;
const std::string kNode = "/handeye_eye_on_hand/object_localizer/";

struct Rig {
  ros::NodeHandle nh;
  ros::Publisher calibration = nh.advertise<PoseWithCovarianceStamped>("/handeye_eye_on_hand/handeye_calibration/calibration", 1, true);
  ros::Publisher detections = nh.advertise<PoseWithCovarianceStamped>("/object_detections", 10);
  tf2_ros::TransformBroadcaster tf;
  std::optional<PoseWithCovarianceStamped> object;
  std::string refusal;
  ros::Subscriber object_sub = nh.subscribe<PoseWithCovarianceStamped>(
      kNode + "object_pose", 10, [this](const PoseWithCovarianceStamped::ConstPtr& m) { object = *m; });
  ros::Subscriber refusal_sub = nh.subscribe<std_msgs::String>(
      kNode + "refusal", 10, [this](const std_msgs::String::ConstPtr& m) { refusal = m->data; });

  void publish_effector(const Eigen::Isometry3d& E, const ros::Time& stamp) {
    geometry_msgs::TransformStamped msg;
    msg.header.stamp = stamp;
    msg.header.frame_id = "base_link";
    msg.child_frame_id = "tool0";
    msg.transform = conversions::to_transform_msg(E);
    tf.sendTransform(msg);
  }
  PoseWithCovarianceStamped detection(const PoseWithCovariance& P, const ros::Time& stamp,
                                      const std::string& frame = "camera_optical_frame") {
    PoseWithCovarianceStamped msg;
    msg.header.stamp = stamp;
    msg.header.frame_id = frame;
    msg.pose = conversions::to_msg(P);
    return msg;
  }
  /// Publishes the detection and waits for an output or a refusal.
  bool send(const PoseWithCovarianceStamped& msg) {
    object.reset();
    refusal.clear();
    detections.publish(msg);
    return test::wait_for([&] { return object.has_value() || !refusal.empty(); }, 10.0);
  }
};

TEST(ObjectLocalizer, PublishesEq68WithTheThreeCovariancesAndRefusesWithReasons) {
  Rig rig;
  Rng rng(21);
  const MeasurementNoise noise = [] {
    MeasurementNoise n;
    n.camera.rotation = std::pow(0.05 * M_PI / 180, 2) * Eigen::Matrix3d::Identity();
    n.camera.translation = std::pow(0.4e-3, 2) * Eigen::Matrix3d::Identity();
    return n;
  }();
  PoseWithCovariance X{typical_X(Setup::EyeInHand), Matrix6d::Zero()};
  X.covariance.diagonal() << 1e-8, 2e-8, 1.5e-8, 1e-7, 2e-7, 3e-7;
  X.covariance(0, 4) = X.covariance(4, 0) = 3e-8;  // an R-t cross term, as the estimator gives
  const Eigen::Isometry3d E = random_pose(rng, 0.5);
  const PoseWithCovariance P{random_view(rng, {}), noise.camera.as_pose_covariance()};

  tf2_ros::Buffer buffer;  // listens from the start, so no broadcast is missed
  tf2_ros::TransformListener listener(buffer);
  // TF at 50 Hz from now on, from a timer so the client keeps spinning.
  ros::Timer tf_timer = rig.nh.createTimer(ros::Duration(0.02), [&](const ros::TimerEvent&) {
    rig.publish_effector(E, ros::Time::now());
  });
  ASSERT_TRUE(test::wait_for([&] { return rig.detections.getNumSubscribers() > 0; }, 20.0));

  // 1. Before any calibration: refused, with the fix.
  test::wait_for([] { return false; }, 0.3);  // spinning: TF keeps flowing
  ASSERT_TRUE(rig.send(rig.detection(P, ros::Time::now() - ros::Duration(0.1))));
  EXPECT_FALSE(rig.object);
  EXPECT_NE(rig.refusal.find("no_calibration"), std::string::npos) << rig.refusal;

  // 2. With X: eq. (68) with the robot's sigmas from the launch file (0.05 mm, 0.01 deg).
  PoseWithCovarianceStamped calibration;
  calibration.header.frame_id = "tool0";
  calibration.pose = conversions::to_msg(X);
  rig.calibration.publish(calibration);
  test::wait_for([] { return false; }, 0.5);
  const ros::Time stamp = ros::Time::now() - ros::Duration(0.1);
  ASSERT_TRUE(rig.send(rig.detection(P, stamp)));
  ASSERT_TRUE(rig.object) << rig.refusal;
  ObjectPoseInput in;
  in.X = X;
  in.T_camera_object = P;
  const double t = 0.05e-3, r = 0.01 * M_PI / 180;
  in.T_base_effector.pose = E;
  in.T_base_effector.covariance.diagonal() << t * t, t * t, t * t, r * r, r * r, r * r;
  const ObjectPose expected = object_in_base(in);
  const PoseWithCovariance got = conversions::to_core(rig.object->pose);
  EXPECT_EQ(rig.object->header.frame_id, "base_link");
  EXPECT_EQ(rig.object->header.stamp, stamp);
  EXPECT_LT((got.pose.translation() - expected.T_base_object.pose.translation()).norm(), 1e-6);
  EXPECT_LT(Eigen::AngleAxisd(got.pose.linear() * expected.T_base_object.pose.linear().transpose()).angle(), 1e-6);
  EXPECT_TRUE(got.covariance.isApprox(expected.T_base_object.covariance, 1e-6))
      << got.covariance << "\n\n" << expected.T_base_object.covariance;

  // ... and the TF base_link -> object at the detection's stamp.
  ASSERT_TRUE(rig.send(rig.detection(P, stamp + ros::Duration(0.01))));
  EXPECT_TRUE(test::wait_for([&] { return buffer.canTransform("base_link", "object", ros::Time(0)); }, 5.0));

  // 3. Refusals: another camera's frame, no robot TF at the stamp, no covariance at all, invalid numbers.
  ASSERT_TRUE(rig.send(rig.detection(P, ros::Time::now() - ros::Duration(0.1), "other_camera")));
  EXPECT_FALSE(rig.object);
  EXPECT_NE(rig.refusal.find("detection_frame"), std::string::npos) << rig.refusal;
  ASSERT_TRUE(rig.send(rig.detection(P, ros::Time(1.0))));
  EXPECT_FALSE(rig.object);
  EXPECT_NE(rig.refusal.find("no_robot_tf"), std::string::npos) << rig.refusal;
  ASSERT_TRUE(rig.send(rig.detection({P.pose, Matrix6d::Zero()}, ros::Time::now() - ros::Duration(0.1))));
  EXPECT_FALSE(rig.object);
  EXPECT_NE(rig.refusal.find("no_detection_covariance"), std::string::npos) << rig.refusal;
  PoseWithCovarianceStamped not_unit = rig.detection(P, ros::Time::now() - ros::Duration(0.1));
  not_unit.pose.pose.orientation.w += 0.5;
  ASSERT_TRUE(rig.send(not_unit));
  EXPECT_FALSE(rig.object);
  EXPECT_NE(rig.refusal.find("invalid_input"), std::string::npos) << rig.refusal;
  EXPECT_NE(rig.refusal.find("QuaternionNotUnit"), std::string::npos) << rig.refusal;
  PoseWithCovarianceStamped negative = rig.detection(P, ros::Time::now() - ros::Duration(0.1));
  negative.pose.covariance[0] = -1e-6;  // a negative variance
  ASSERT_TRUE(rig.send(negative));
  EXPECT_FALSE(rig.object);
  EXPECT_NE(rig.refusal.find("invalid_input"), std::string::npos) << rig.refusal;

  // 4. A calibration for the wrong parent frame is ignored, X stays.
  calibration.header.frame_id = "base_link";
  rig.calibration.publish(calibration);
  EXPECT_TRUE(test::wait_for([&] { return rig.refusal.find("calibration_frame") != std::string::npos; }, 5.0)) << rig.refusal;
  ASSERT_TRUE(rig.send(rig.detection(P, ros::Time::now() - ros::Duration(0.1))));
  EXPECT_TRUE(rig.object) << rig.refusal;
}

}  // namespace
}  // namespace handeye

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_object_localizer");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
