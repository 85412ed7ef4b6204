// Offline replay of simulated bags: the truth within the predicted uncertainty,
// and a clear named error for each kind of bad bag.
#include <gtest/gtest.h>
#include <ros/time.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "handeye_covariance/estimation/estimator.h"
#include "handeye_covariance/io/yaml_io.h"
#include "handeye_covariance/simulation/monte_carlo.h"
#include "handeye_covariance/corners/corner_calibration.h"
#include "handeye_covariance/ros/bag.h"

namespace handeye {
namespace {

std::string temp(const std::string& name) { return ::testing::TempDir() + "/bag_" + name; }

void expect_error(const std::string& bag, ErrorCode code, const std::string& mentions,
                  const SessionConfig& config = {}) {
  try {
    replay_bag(bag, config);
    ADD_FAILURE() << "expected " << to_string(code);
  } catch (const HandEyeError& e) {
    EXPECT_EQ(e.code(), code) << e.what();
    EXPECT_NE(std::string(e.what()).find(mentions), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("Fix:"), std::string::npos) << e.what();
  }
}

void expect_recovers_truth(Setup setup, unsigned seed) {
  BagSimulationOptions options;
  options.setup = setup;
  options.seed = seed;
  const std::string path = temp(std::string(to_string(setup)) + ".bag");
  const SimulatedBag bag = write_simulated_bag(path, options);
  EXPECT_LT(std::filesystem::file_size(path), 2u * 1024 * 1024);
  SessionConfig config;
  config.rig.setup = setup;
  const BagReplay replay = replay_bag(path, config);
  EXPECT_EQ(replay.messages.at("/tf"), bag.tf_messages);
  EXPECT_EQ(replay.detections, bag.detections);
  EXPECT_GE(static_cast<int>(replay.samples.samples.size()), options.poses - 1);
  EXPECT_LE(static_cast<int>(replay.samples.samples.size()), options.poses);
  ASSERT_TRUE(replay.samples.noise.has_value()) << "the detections' covariance is the noise model";
  const Calibration c = solve(replay.samples);
  const Vector6d error = pose_error(c.T_parent_camera, bag.X);
  // Within 3 sigma on every axis, and jointly below the chi2(6) 99.7% quantile.
  for (int i = 0; i < 6; ++i) EXPECT_LT(std::abs(error(i)), 3.0 * std::sqrt(c.pose_covariance(i, i))) << i;
  EXPECT_LT(error.dot(c.pose_covariance.ldlt().solve(error)), 20.06);
}

TEST(Bag, ReplayRecoversTheTruthEyeInHand) { expect_recovers_truth(Setup::EyeInHand, 3); }
TEST(Bag, ReplayRecoversTheTruthEyeToHand) { expect_recovers_truth(Setup::EyeToHand, 4); }

TEST(Bag, EveryDetectionInputOfTheNode) {
  for (const std::string type : {"tags", "pose_with_covariance", "pose", "tf"}) {
    BagSimulationOptions options;
    options.detection_type = type;
    options.poses = 8;
    const std::string path = temp(type + ".bag");
    const SimulatedBag bag = write_simulated_bag(path, options);
    SessionConfig config;
    config.detection_input = type;
    const BagReplay replay = replay_bag(path, config);
    EXPECT_GE(replay.samples.samples.size(), 7u) << type;
    // Only the covariance-carrying kinds give a noise model; the others estimate it.
    EXPECT_EQ(replay.samples.noise.has_value(), type == "tags" || type == "pose_with_covariance") << type;
    const Calibration c = solve(replay.samples);
    const Vector6d error = pose_error(c.T_parent_camera, bag.X);
    EXPECT_LT(error.dot(c.pose_covariance.ldlt().solve(error)), 20.06) << type;
  }
}

// A bag of camera images instead of detections (`handeye bag --target`): the
// target detector runs on every image, the pose of each under the pixel sigma
// pooled over them all, and X comes out within its predicted uncertainty.
BagSimulationOptions image_bag(const std::string& target_file) {
  BagSimulationOptions options;
  options.detection_type = "images";
  options.target = io::read_target(target_file);
  options.poses = 8;
  options.pause = 2.0;  // the sampler's still_window (1 s) and a few frames to spare
  options.move = 0.5;
  options.detection_rate = 4.0;
  return options;
}

std::string target_file(const std::string& name) { return std::string(HANDEYE_SOURCE_DIR) + "/config/" + name; }

TEST(Bag, ImagesOfEveryTargetKind) {
  for (const std::string name : {"targets/chessboard.yaml", "targets/charuco.yaml", "targets/aruco.yaml",
                                 "targets/apriltag.yaml", "tag_board_2x2.yaml"}) {
    BagSimulationOptions options = image_bag(target_file(name));
    options.compressed = name == "targets/charuco.yaml";  // one kind as sensor_msgs/CompressedImage
    options.seed = 11;
    const std::string path = temp("images.bag");
    const SimulatedBag bag = write_simulated_bag(path, options);
    SessionConfig config;
    config.target_file = target_file(name);
    SessionSettings settings = session_settings(config);
    settings.session_file.clear();
    CalibrationSession session(settings);
    const BagReplay replay = replay_bag(path, config, session);
    EXPECT_EQ(replay.images, bag.detections) << name;
    EXPECT_EQ(replay.image_topic, options.compressed ? "/camera/image_raw/compressed" : "/camera/image_raw") << name;
    EXPECT_EQ(replay.camera_info_topic, "/camera/camera_info") << name;
    EXPECT_GE(replay.detections, bag.detections - 2) << name;
    EXPECT_GE(replay.samples.samples.size(), 7u) << name;
    const Calibration c = session.calibrate(session.snapshot());  // as `handeye bag` does: the joint estimator
    const Vector6d error = pose_error(c.T_parent_camera, bag.X);
    const double nees = error.dot(c.pose_covariance.ldlt().solve(error));
    std::printf("%-26s %d images, %d detected, pixel sigma %.3f px, %zu samples, X error %.3f mm, NEES %.2f\n",
                name.c_str(), replay.images, replay.detections, replay.pixel_sigma, replay.samples.samples.size(),
                error.head<3>().norm() * 1e3, nees);
    EXPECT_LT(nees, 20.06) << name;
  }
}

// `handeye bag` with `method: corners`: the replay keeps each image's corners with
// its sample, and the session refines the joint estimate from them.
TEST(Bag, ImagesWithMethodCorners) {
  BagSimulationOptions options = image_bag(target_file("targets/chessboard.yaml"));
  options.seed = 12;
  const std::string path = temp("images_corners.bag");
  const SimulatedBag bag = write_simulated_bag(path, options);
  SessionConfig config;
  config.target_file = target_file("targets/chessboard.yaml");
  config.method = "corners";
  SessionSettings settings = session_settings(config);
  settings.session_file.clear();
  settings.refine_corners = corner_refiner();
  CalibrationSession session(settings);
  const BagReplay replay = replay_bag(path, config, session);
  ASSERT_GE(replay.samples.samples.size(), 7u);
  for (const PoseSample& sample : replay.samples.samples) {
    ASSERT_TRUE(sample.corners);
    EXPECT_EQ(sample.corners->points.object.size(), 54u);  // the 9 x 6 inner corners
    EXPECT_EQ(sample.corners->source.rfind("image at ", 0), 0u) << sample.corners->source;
  }
  const Calibration c = session.calibrate(session.snapshot());
  EXPECT_EQ(c.method, Method::Corners);
  ASSERT_TRUE(c.corner_fit);
  EXPECT_EQ(static_cast<int>(c.corner_fit->images.size()), c.samples_used);
  const Vector6d error = pose_error(c.T_parent_camera, bag.X);
  const double nees = error.dot(c.pose_covariance.ldlt().solve(error));
  std::printf("corners: %d images, pixel sigma %.3f px, RMS %.3f px, X error %.3f mm, NEES %.2f\n", c.samples_used,
              c.corner_fit->pixel_sigma, c.corner_fit->rms_px, error.head<3>().norm() * 1e3, nees);
  EXPECT_LT(nees, 22.46);  // chi^2(6) at 0.999
}

TEST(Bag, ImagesNeedTheTargetAndTheirCameraInfo) {
  const std::string path = temp("images_errors.bag");
  write_simulated_bag(path, image_bag(target_file("targets/chessboard.yaml")));
  expect_error(path, ErrorCode::NoData, "but no target to look for");
  SessionConfig config;
  config.target_file = target_file("targets/charuco.yaml");  // not the printed one
  expect_error(path, ErrorCode::NoData, "the target was found in none of the", config);
  config.target_file = target_file("targets/chessboard.yaml");
  config.image_topic = "/camera/image_rect";
  expect_error(path, ErrorCode::NoData, "`/camera/image_rect` is not in the bag; the bag's image topics are: /camera/image_raw",
               config);
  config.image_topic.clear();
  config.camera_info_topic = "/tf";
  expect_error(path, ErrorCode::NoData, "no CameraInfo for `/camera/image_raw`", config);
}

TEST(Bag, ReplayIsDeterministic) {
  const std::string path = temp("twice.bag");
  write_simulated_bag(path, {});
  const BagReplay a = replay_bag(path, {}), b = replay_bag(path, {});
  ASSERT_EQ(a.samples.samples.size(), b.samples.samples.size());
  for (std::size_t i = 0; i < a.samples.samples.size(); ++i) EXPECT_EQ(*a.samples.samples[i].stamp, *b.samples.samples[i].stamp);
}

TEST(Bag, NoDetections) {
  BagSimulationOptions options;
  options.detections = false;
  write_simulated_bag(temp("nodet.bag"), options);
  expect_error(temp("nodet.bag"), ErrorCode::NoData, "no topic `/tag_detections`");
}

TEST(Bag, MissingRobotTfLink) {
  BagSimulationOptions options;
  options.robot_tf = false;
  write_simulated_bag(temp("notf.bag"), options);
  expect_error(temp("notf.bag"), ErrorCode::NoData, "no TF base_link -> tool0");
}

TEST(Bag, WrongTopicName) {
  write_simulated_bag(temp("topic.bag"), {});
  SessionConfig config;
  config.detections_topic = "/apriltag/detections";
  expect_error(temp("topic.bag"), ErrorCode::NoData, "its topics are: /tag_detections, /tf, /tf_static", config);
}

TEST(Bag, TruncatedAndCorruptFiles) {
  write_simulated_bag(temp("whole.bag"), {});
  {  // a recording killed half way
    std::ifstream in(temp("whole.bag"), std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::ofstream(temp("truncated.bag"), std::ios::binary) << bytes.substr(0, bytes.size() / 2);
    std::string corrupt = bytes;
    for (std::size_t i = 20; i < corrupt.size(); i += 97) corrupt[i] = static_cast<char>(corrupt[i] ^ 0x5a);
    std::ofstream(temp("corrupt.bag"), std::ios::binary) << corrupt;
  }
  expect_error(temp("truncated.bag"), ErrorCode::IoError, "rosbag reindex");
  expect_error(temp("corrupt.bag"), ErrorCode::IoError, "bag");
  std::ofstream(temp("text.bag")) << "not a bag\n";
  expect_error(temp("text.bag"), ErrorCode::IoError, "cannot read the bag");
  expect_error(temp("absent.bag"), ErrorCode::IoError, "cannot read the bag");
}

}  // namespace
}  // namespace handeye

int main(int argc, char** argv) {
  ros::Time::init();
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
