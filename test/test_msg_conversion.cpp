// Round trips across the only ROS <-> Eigen seam.
#include <gtest/gtest.h>

#include <functional>

#include "handeye_covariance/ros/msg_conversion.h"
#include "handeye_covariance/ros/observations.h"
#include "handeye_covariance/session/session_config.h"

#include <tf2/buffer_core.h>
#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/simulation/pattern_renderer.h"
#include "test_helpers.h"

namespace handeye {
namespace {

TEST(MsgConversion, PoseAndTransformRoundTrip) {
  Rng rng(1);
  for (int i = 0; i < 20; ++i) {
    const Eigen::Isometry3d T = random_pose(rng, 2.0);
    EXPECT_LE((conversions::to_eigen(conversions::to_pose_msg(T)).matrix() - T.matrix()).norm(), 1e-14);
    EXPECT_LE((conversions::to_eigen(conversions::to_transform_msg(T)).matrix() - T.matrix()).norm(), 1e-14);
  }
}

TEST(MsgConversion, CovarianceIsRowMajorInRosOrder) {
  PoseWithCovariance p;
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c) p.covariance(r, c) = 10 * r + c;
  const geometry_msgs::PoseWithCovariance msg = conversions::to_msg(p);
  EXPECT_EQ(msg.covariance[1], 1.0);   // (x, y)
  EXPECT_EQ(msg.covariance[6], 10.0);  // (y, x)
  EXPECT_EQ(msg.covariance[35], 55.0); // (rz, rz)
  EXPECT_EQ(conversions::to_core(msg).covariance, p.covariance);
}

TEST(MsgConversion, FullCovarianceOnlyWhenNonZero) {
  boost::array<double, 36> zeros{};
  EXPECT_FALSE(conversions::covariance_if_nonzero(zeros).has_value());
  boost::array<double, 36> c{};
  c[0] = 1e-6;   // x x
  c[35] = 4e-6;  // rz rz
  c[5] = 9e-7;   // x-rz: the cross block is kept, not cut at the ROS boundary
  c[30] = 9e-7;
  const auto full = conversions::covariance_if_nonzero(c);
  ASSERT_TRUE(full.has_value());
  EXPECT_EQ((*full)(0, 0), 1e-6);
  EXPECT_EQ((*full)(5, 5), 4e-6);
  EXPECT_EQ((*full)(0, 5), 9e-7);
  EXPECT_EQ(PoseNoise::from_pose_covariance(*full).translation_rotation(0, 2), 9e-7);
}

TEST(MsgConversion, QuaternionNorm) {
  geometry_msgs::Quaternion q;
  q.w = 2.0;
  EXPECT_DOUBLE_EQ(conversions::quaternion_norm(q), 2.0);
}

// Every refusal of the detection -> sample path the node and the bag replay share,
// each with its stable kind and a message that says what to fix.
}  // namespace
}  // namespace handeye

namespace handeye {
namespace {

TEST(CameraInfoConversion, RoundTripsAndRefusesUncalibratedCameras) {
  const CameraModel camera = simulated_camera();
  sensor_msgs::CameraInfo info = conversions::to_camera_info(camera);
  EXPECT_EQ(info.distortion_model, "plumb_bob");
  const CameraModel back = conversions::to_camera_model(info);
  EXPECT_EQ(back.K, camera.K);
  EXPECT_EQ(back.distortion, camera.distortion);
  EXPECT_EQ(back.width, 640);
  EXPECT_EQ(info.K[2], camera.K(0, 2));  // row-major: K[2] is cx

  sensor_msgs::CameraInfo uncalibrated = info;
  uncalibrated.K.fill(0.0);
  try {
    conversions::to_camera_model(uncalibrated);
    FAIL() << "accepted K = 0";
  } catch (const HandEyeError& e) {
    EXPECT_NE(std::string(e.what()).find("not calibrated"), std::string::npos) << e.what();
  }
  sensor_msgs::CameraInfo fisheye = info;
  fisheye.distortion_model = "equidistant";
  EXPECT_THROW(conversions::to_camera_model(fisheye), HandEyeError);
  sensor_msgs::CameraInfo odd = info;
  odd.D.resize(3);
  EXPECT_THROW(conversions::to_camera_model(odd), HandEyeError);
}

// Every refusal of the detection -> sample path the node and the bag replay share,
// each with its stable kind and a message that says what to fix.
// A detection's corners travel in TagDetection and come back as they were; a
// detection without them has none, and inconsistent ones are refused by kind.
TEST(MsgConversion, ADetectionsCornersRoundTrip) {
  TargetCorners corners;
  corners.camera.K << 605.0, 0.0, 320.5, 0.0, 604.0, 240.25, 0.0, 0.0, 1.0;
  corners.camera.distortion = {0.1, -0.2, 1e-3, -2e-3, 0.05};
  corners.camera.width = 640;
  corners.camera.height = 480;
  for (int i = 0; i < 4; ++i) {
    corners.points.object.emplace_back(0.02 * i, -0.01 * i, 0.0);
    corners.points.image.emplace_back(300.0 + 1.5 * i, 220.0 - 0.25 * i);
  }
  corners.points.ids = {7};
  corners.points.blocks = 8;
  const Eigen::MatrixXd A = Eigen::MatrixXd::Random(8, 8);
  corners.points.corner_covariance = A * A.transpose() + Eigen::MatrixXd::Identity(8, 8);
  TagDetection detection;
  EXPECT_FALSE(conversions::to_corners(detection));
  conversions::set_corners(corners, detection);
  const std::shared_ptr<TargetCorners> back = conversions::to_corners(detection);
  ASSERT_TRUE(back);
  EXPECT_EQ(back->camera.K, corners.camera.K);
  EXPECT_EQ(back->camera.distortion, corners.camera.distortion);
  EXPECT_EQ(back->points.object, corners.points.object);
  EXPECT_EQ(back->points.image, corners.points.image);
  EXPECT_EQ(back->points.ids, corners.points.ids);
  EXPECT_EQ(back->points.corner_covariance, corners.points.corner_covariance);

  TagDetectionArray tags;
  tags.header.stamp = ros::Time(10.5);
  detection.pose.pose.pose.orientation.w = 1.0;
  tags.detections = {detection};
  std::optional<Refusal> refusal;
  std::optional<Detection> chosen = select_detection(tags, {}, refusal);
  ASSERT_TRUE(chosen && chosen->corners);
  EXPECT_EQ(chosen->corners->source, "image at 10.5 s");
  // Unusable corners are dropped with the reason; the pose is kept (method joint needs only it).
  const auto problem_of = [&](const std::function<void(TagDetection&)>& edit) {
    tags.detections[0] = detection;
    edit(tags.detections[0]);
    const std::optional<Detection> d = select_detection(tags, {}, refusal);
    EXPECT_FALSE(refusal);
    if (!d) return std::string("no detection");
    EXPECT_FALSE(d->corners);
    return d->corners_problem;
  };
  EXPECT_NE(problem_of([](TagDetection& d) { d.image_points.pop_back(); }).find("image_points"), std::string::npos);
  EXPECT_NE(problem_of([](TagDetection& d) { d.camera_info.K[0] = 0.0; }).find("pinhole"), std::string::npos);
  EXPECT_NE(problem_of([](TagDetection& d) { d.corner_covariance.resize(10); }).find("corner_covariance"), std::string::npos);
  EXPECT_NE(problem_of([](TagDetection& d) { d.corner_covariance[0] = -1.0; }).find("positive definite"), std::string::npos);
  EXPECT_NE(problem_of([](TagDetection& d) { d.corner_block = 32; }).find("corner_block"), std::string::npos);
  EXPECT_NE(problem_of([](TagDetection& d) { d.object_points.resize(1001); }).find("at most 1000"), std::string::npos);
  // make_observation carries the reason on.
  tf2::BufferCore tf;
  geometry_msgs::TransformStamped robot;
  robot.header.frame_id = "base_link";
  robot.child_frame_id = "tool0";
  robot.transform.rotation.w = 1.0;
  robot.header.stamp = ros::Time(10.5);
  tf.setTransform(robot, "test");
  tags.detections[0] = detection;
  tags.detections[0].image_points.pop_back();
  const ObservationResult r = make_observation(tf, SessionConfig{}.rig, *select_detection(tags, {}, refusal));
  ASSERT_TRUE(r.observation);
  EXPECT_FALSE(r.observation->corners);
  EXPECT_NE(r.corners_dropped.find("image_points"), std::string::npos) << r.corners_dropped;
}

TEST(Observations, EveryBadDetectionIsRefusedWithItsKindAndReason) {
  tf2::BufferCore tf;
  geometry_msgs::TransformStamped robot;
  robot.header.frame_id = "base_link";
  robot.child_frame_id = "tool0";
  robot.transform.rotation.w = 1.0;
  for (double t : {10.0, 11.0}) {
    robot.header.stamp = ros::Time(t);
    tf.setTransform(robot, "test");
  }
  const SessionConfig config;
  Detection good;
  good.stamp = ros::Time(10.5);
  good.pose.orientation.w = 1.0;
  good.pose.position.z = 0.5;
  ASSERT_TRUE(make_observation(tf, config.rig, good).observation);

  struct Row {
    std::string kind, mentions;
    std::function<void(Detection&)> edit;
  };
  const std::vector<Row> rows = {
      {"zero_stamp", "image time", [](Detection& d) { d.stamp = ros::Time(); }},
      {"bad_quaternion", "unit quaternion", [](Detection& d) { d.pose.orientation.w = 1.5; }},
      {"bad_quaternion", "norm nan", [](Detection& d) { d.pose.orientation.x = std::nan(""); }},
      {"bad_covariance", "all-zero covariance",
       [](Detection& d) { d.covariance = DecoupledCovariance{-Eigen::Matrix3d::Identity(), Eigen::Matrix3d::Identity()}.as_pose_covariance(); }},
      {"bad_covariance", "cross block",  // each block fine, but a correlation of 2 between x and rx
       [](Detection& d) {
         Matrix6d c = 1e-6 * Matrix6d::Identity();
         c(0, 3) = c(3, 0) = 2e-6;
         d.covariance = c;
       }},
      {"bad_position", "NaN or Inf", [](Detection& d) { d.pose.position.y = INFINITY; }},
      {"no_robot_tf", "robot state publisher", [](Detection& d) { d.stamp = ros::Time(12.0); }},
      {"detection_frame", "tracking_base_frame", [](Detection& d) { d.frame = "other_camera"; }},
  };
  for (const Row& row : rows) {
    Detection d = good;
    row.edit(d);
    const ObservationResult r = make_observation(tf, config.rig, d);
    ASSERT_TRUE(r.refusal) << row.kind;
    EXPECT_FALSE(r.observation) << row.kind;
    EXPECT_EQ(r.refusal->kind, row.kind);
    EXPECT_NE(r.refusal->message.find(row.mentions), std::string::npos) << r.refusal->message;
  }

  // Choosing the pattern among the tags of a message.
  TagDetectionArray tags;
  tags.header.stamp = ros::Time(10.5);
  TagDetection a, b;
  a.id = {3};
  b.id = {4};
  a.pose.pose.pose = b.pose.pose.pose = good.pose;
  tags.detections = {a, b};
  std::optional<Refusal> refusal;
  EXPECT_FALSE(select_detection(tags, {}, refusal));
  ASSERT_TRUE(refusal);
  EXPECT_NE(refusal->message.find("tag_ids"), std::string::npos) << refusal->message;
  refusal.reset();
  EXPECT_FALSE(select_detection(tags, {0}, refusal));
  ASSERT_TRUE(refusal);
  EXPECT_NE(refusal->message.find("tag_ids"), std::string::npos) << refusal->message;
  refusal.reset();
  const std::optional<Detection> chosen = select_detection(tags, {4}, refusal);
  EXPECT_FALSE(refusal);
  ASSERT_TRUE(chosen);
  EXPECT_EQ(chosen->stamp, ros::Time(10.5));
}

// A detection stamped in camera_link while X is for camera_optical_frame: the
// pose is moved into the optical frame and so is its covariance. A depth-heavy
// covariance (camera_link's x is the viewing direction) must land on the
// optical z axis, the cross block with it; before this, the depth variance
// stayed on x, where it says the lateral position is poorly known.
TEST(Observations, ADetectionInAnotherCameraFrameMovesItsCovarianceWithItsPose) {
  tf2::BufferCore tf;
  geometry_msgs::TransformStamped robot;
  robot.header.frame_id = "base_link";
  robot.child_frame_id = "tool0";
  robot.header.stamp = ros::Time(10.0);
  robot.transform.rotation.w = 1.0;
  tf.setTransform(robot, "test", true);
  // The usual driver TF: camera_link (x forward, y left, z up) -> optical (z forward, x right, y down).
  const Eigen::Matrix3d R_link_optical = (Eigen::Matrix3d() << 0, 0, 1, -1, 0, 0, 0, -1, 0).finished();
  const Eigen::Isometry3d T_link_optical = se3::make_pose(R_link_optical, Eigen::Vector3d(0.01, 0.015, 0.0));
  geometry_msgs::TransformStamped optical;
  optical.header.frame_id = "camera_link";
  optical.child_frame_id = "camera_optical_frame";
  optical.transform = conversions::to_transform_msg(T_link_optical);
  tf.setTransform(optical, "test", true);

  // In camera_link: depth (x) 25x the lateral variance, tilt about y and z 9x the roll about x.
  const double lateral = std::pow(0.3e-3, 2), tilt = std::pow(0.15 * M_PI / 180, 2);
  Matrix6d link_covariance = Matrix6d::Zero();
  link_covariance.diagonal() << 25 * lateral, lateral, lateral, tilt / 9, tilt, tilt;
  link_covariance(0, 4) = link_covariance(4, 0) = 0.5 * std::sqrt(25 * lateral * tilt);  // depth with tilt
  const Eigen::Isometry3d T_link_pattern = se3::make_pose(so3::exp(Eigen::Vector3d(0.1, -0.2, 0.3)), Eigen::Vector3d(0.6, 0.05, -0.02));
  Detection d;
  d.stamp = ros::Time(10.0);
  d.frame = "camera_link";
  d.pose = conversions::to_pose_msg(T_link_pattern);
  d.covariance = link_covariance;
  const ObservationResult r = make_observation(tf, SessionConfig{}.rig, d);
  ASSERT_TRUE(r.observation) << r.refusal->message;
  const Eigen::Isometry3d expected_pose = T_link_optical.inverse() * T_link_pattern;
  EXPECT_LE((r.observation->T_camera_pattern.matrix() - expected_pose.matrix()).norm(), 1e-12);
  ASSERT_TRUE(r.observation->pattern_noise);
  const Matrix6d C = r.observation->pattern_noise->as_pose_covariance();
  // The adjoint of a fixed frame change: blkdiag(R, R) with R = R_optical_link.
  Matrix6d Ad = Matrix6d::Zero();
  Ad.topLeftCorner<3, 3>() = Ad.bottomRightCorner<3, 3>() = R_link_optical.transpose();
  EXPECT_LE((C - Ad * link_covariance * Ad.transpose()).norm(), 1e-18);
  EXPECT_NEAR(C(2, 2), 25 * lateral, 1e-15) << "the depth variance is on the optical axis";
  EXPECT_NEAR(C(0, 0), lateral, 1e-15);
  EXPECT_NEAR(C(1, 1), lateral, 1e-15);
  EXPECT_NEAR(C(5, 5), tilt / 9, 1e-15) << "the roll about the optical axis";
  // The cross block moved too: link (x, ry) is optical (z, -rx).
  EXPECT_NEAR(C(2, 3), -0.5 * std::sqrt(25 * lateral * tilt), 1e-15);
  EXPECT_EQ(C(0, 4), 0.0);
}

}  // namespace
}  // namespace handeye

namespace handeye {
namespace {

geometry_msgs::TransformStamped edge(const std::string& parent, const std::string& child, const Eigen::Isometry3d& T) {
  geometry_msgs::TransformStamped t;
  t.header.frame_id = parent;
  t.child_frame_id = child;
  t.transform = conversions::to_transform_msg(T);
  return t;
}

// Where /calibrate puts X in TF: above the camera driver's own tree, so that
// every frame keeps one parent; never beside a link that already connects the
// camera to the robot.
TEST(CameraTfEdge, XGoesAboveTheCamerasOwnTreeAndNeverGivesAFrameASecondParent) {
  const Rig rig = SessionConfig{}.rig;  // tool0, camera_optical_frame
  Rng rng(5);
  const Eigen::Isometry3d X = random_pose(rng, 0.2), T_link_optical = random_pose(rng, 0.05);

  tf2::BufferCore bare;  // no driver tree: X itself, tool0 -> camera_optical_frame
  CameraTfEdge e = camera_tf_edge(bare, rig, X, "");
  EXPECT_TRUE(e.refusal.empty()) << e.refusal;
  EXPECT_EQ(e.parent, "tool0");
  EXPECT_EQ(e.child, "camera_optical_frame");
  EXPECT_TRUE(e.transform.isApprox(X));

  tf2::BufferCore driver;  // camera_link -> camera_optical_frame: tool0 -> camera_link = X T_optical_link
  driver.setTransform(edge("camera_link", "camera_optical_frame", T_link_optical), "driver", true);
  e = camera_tf_edge(driver, rig, X, "");
  ASSERT_TRUE(e.refusal.empty()) << e.refusal;
  EXPECT_EQ(e.child, "camera_link");
  EXPECT_TRUE((e.transform * T_link_optical).isApprox(X, 1e-12));

  // Our own edge from an earlier /calibrate is found and replaced, not refused.
  driver.setTransform(edge("tool0", "camera_link", e.transform), "us", true);
  const Eigen::Isometry3d X2 = random_pose(rng, 0.2);
  e = camera_tf_edge(driver, rig, X2, "camera_link");
  ASSERT_TRUE(e.refusal.empty()) << e.refusal;
  EXPECT_EQ(e.child, "camera_link");
  EXPECT_TRUE((e.transform * T_link_optical).isApprox(X2, 1e-12));

  // A URDF that already mounts the camera on the robot: publishing would make a second path.
  tf2::BufferCore urdf;
  urdf.setTransform(edge("camera_link", "camera_optical_frame", T_link_optical), "driver", true);
  urdf.setTransform(edge("tool0", "camera_mount", Eigen::Isometry3d::Identity()), "urdf", true);
  urdf.setTransform(edge("camera_mount", "camera_link", Eigen::Isometry3d::Identity()), "urdf", true);
  e = camera_tf_edge(urdf, rig, X, "");
  EXPECT_NE(e.refusal.find("already connected to tool0"), std::string::npos) << e.refusal;
  // The driver's tree arrived after a first /calibrate had hung the optical frame off tool0:
  // the driver re-parents that frame, and X moves above camera_link.
  tf2::BufferCore late;
  late.setTransform(edge("tool0", "camera_optical_frame", X), "us", true);
  late.setTransform(edge("camera_link", "camera_optical_frame", T_link_optical), "driver", true);
  e = camera_tf_edge(late, rig, X, "camera_optical_frame");
  ASSERT_TRUE(e.refusal.empty()) << e.refusal;
  EXPECT_EQ(e.child, "camera_link");

  // Two publishers that disagree can make a loop; the walk stops and says so.
  tf2::BufferCore loop;
  loop.setTransform(edge("camera_link", "camera_optical_frame", T_link_optical), "a", true);
  loop.setTransform(edge("camera_optical_frame", "camera_link", T_link_optical.inverse()), "b", true);
  e = camera_tf_edge(loop, rig, X, "");
  EXPECT_NE(e.refusal.find("loop"), std::string::npos) << e.refusal;
}

}  // namespace
}  // namespace handeye
