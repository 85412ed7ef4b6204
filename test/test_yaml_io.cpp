#include <gtest/gtest.h>

#include <yaml-cpp/yaml.h>

#include <cstdlib>
#include <filesystem>
#include <functional>
#include <sstream>

#include "handeye_covariance/estimation/joint_estimator.h"
#include "handeye_covariance/io/yaml_io.h"
#include "easy_handeye_file.h"
#include "sections.h"
#include "test_sections.h"
#include "scratch_directory.h"
#include "test_helpers.h"

namespace handeye {
namespace {

using Eigen::Isometry3d;

void expect_same_pose(const Isometry3d& a, const Isometry3d& b) {
  EXPECT_LE((a.matrix() - b.matrix()).norm(), 1e-15);
}

void expect_parse_error(const std::string& text, ErrorCode code, const std::string& mentions) {
  try {
    io::parse_samples(text, "test.yaml");
    ADD_FAILURE() << "expected " << to_string(code);
  } catch (const HandEyeError& e) {
    EXPECT_EQ(e.code(), code) << e.what();
    EXPECT_NE(std::string(e.what()).find(mentions), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("Fix:"), std::string::npos) << e.what();
  }
}

const char* kValid = R"(setup: eye_in_hand
samples:
  - effector: {translation: [0.1, 0.2, 0.3], rotation: [0, 0, 0, 1]}
    pattern: {translation: [0, 0, 0.5], rotation: [1, 0, 0, 0]}
)";

TEST(YamlIo, SamplesRoundTripExactly) {
  Rng rng(1);
  SimulatedSession s = simulate_session(rng, Setup::EyeToHand, typical_X(Setup::EyeToHand), 7, paper_noise(1e-5));
  s.samples.samples[2].noise = paper_noise(1e-3);
  // A detector's full 6x6: the cross block is written (as `pose`) and read back.
  MeasurementNoise with_cross = paper_noise(1e-4);
  with_cross.camera.translation_rotation << 1e-5, 0, -2e-5, 0, 3e-6, 0, 0, 0, 1e-6;
  s.samples.samples[4].noise = with_cross;
  const SampleSet back = io::parse_samples(io::format_samples(s.samples), "memory");
  EXPECT_EQ(back.rig.setup, Setup::EyeToHand);
  EXPECT_EQ(back.rig.frames.camera, "camera_optical_frame");
  ASSERT_EQ(back.samples.size(), 7u);
  for (std::size_t i = 0; i < 7; ++i) {
    expect_same_pose(back.samples[i].T_base_effector, s.samples.samples[i].T_base_effector);
    expect_same_pose(back.samples[i].T_camera_pattern, s.samples.samples[i].T_camera_pattern);
    EXPECT_EQ(*back.samples[i].stamp, *s.samples.samples[i].stamp);
  }
  ASSERT_TRUE(back.noise.has_value());
  EXPECT_EQ(back.noise->camera.rotation, s.samples.noise->camera.rotation);
  ASSERT_TRUE(back.samples[2].noise.has_value());
  EXPECT_EQ(back.samples[2].noise->robot.translation, paper_noise(1e-3).robot.translation);
  EXPECT_FALSE(back.samples[3].noise.has_value());
  ASSERT_TRUE(back.samples[4].noise.has_value());
  EXPECT_EQ(back.samples[4].noise->camera.as_pose_covariance(), with_cross.camera.as_pose_covariance());
  EXPECT_FALSE(back.samples[4].noise->robot.has_cross_block());
  // The target's geometry the session needs (Rig): its face, its size (the
  // view-following noise) and whether it looks the same turned by 180 degrees.
  EXPECT_FALSE(back.rig.symmetric_face);
  EXPECT_TRUE(back.rig.face_size.isZero(0.0));
  set_target(s.samples.rig, io::parse_target("{type: chessboard, inner_corners: [9, 7], square: 0.025}", "memory"));
  const SampleSet symmetric = io::parse_samples(io::format_samples(s.samples), "memory");
  EXPECT_TRUE(symmetric.rig.symmetric_face);
  EXPECT_TRUE(symmetric.rig.face_size.isApprox(Eigen::Vector2d(0.2, 0.15), 1e-15));
  expect_same_pose(symmetric.rig.T_pattern_face, s.samples.rig.T_pattern_face);
  const Eigen::Isometry3d F = symmetric.rig.face_half_turn();
  EXPECT_LT((F * F).matrix().cwiseAbs().maxCoeff() - 1.0, 1e-15);  // a half turn: F F = I
  EXPECT_TRUE((F * Eigen::Vector3d(0.1, 0.075, 0.0)).isApprox(Eigen::Vector3d(0.1, 0.075, 0.0)));  // about the face's centre
  EXPECT_THROW(io::parse_samples("{setup: eye_in_hand, pattern_symmetric: maybe, samples: []}", "memory"), HandEyeError);
}

// A sample's corners (method corners) survive the session file: camera, points,
// ids and the corner-noise blocks, to the bit; inconsistent sizes are named.
TEST(YamlIo, ASamplesCornersRoundTripExactly) {
  Rng rng(4);
  SimulatedSession s = simulate_session(rng, Setup::EyeInHand, typical_X(Setup::EyeInHand), 3, paper_noise(1e-5));
  TargetCorners corners;
  corners.camera.K << 601.5, 0.0, 321.25, 0.0, 602.75, 239.5, 0.0, 0.0, 1.0;
  corners.camera.distortion = {0.1, -0.2, 1e-3, -2e-3, 0.05};
  corners.camera.width = 640;
  corners.camera.height = 480;
  corners.source = "frame_0007.png";
  std::normal_distribution<double> n(0.0, 1.0);
  for (int i = 0; i < 8; ++i) {
    corners.points.object.emplace_back(0.01 * i, 0.02 * (i % 3), 0.0);
    corners.points.image.emplace_back(100.0 + n(rng), 200.0 + n(rng));
  }
  corners.points.ids = {3, 5};
  corners.points.blocks = 8;
  const Eigen::MatrixXd A = Eigen::MatrixXd::Random(8, 8);
  corners.points.corner_covariance = Eigen::MatrixXd::Zero(16, 16);
  corners.points.corner_covariance.block(0, 0, 8, 8) = A * A.transpose() + Eigen::MatrixXd::Identity(8, 8);
  corners.points.corner_covariance.block(8, 8, 8, 8) = 2.0 * Eigen::MatrixXd::Identity(8, 8);
  s.samples.samples[1].corners = std::make_shared<const TargetCorners>(corners);
  const SampleSet back = io::parse_samples(io::format_samples(s.samples), "memory");
  EXPECT_FALSE(back.samples[0].corners);
  ASSERT_TRUE(back.samples[1].corners);
  const TargetCorners& c = *back.samples[1].corners;
  EXPECT_EQ(c.source, corners.source);
  EXPECT_EQ(c.camera.K, corners.camera.K);
  EXPECT_EQ(c.camera.distortion, corners.camera.distortion);
  EXPECT_EQ(c.camera.width, 640);
  EXPECT_EQ(c.camera.height, 480);
  EXPECT_EQ(c.points.object, corners.points.object);
  EXPECT_EQ(c.points.image, corners.points.image);
  EXPECT_EQ(c.points.ids, corners.points.ids);
  EXPECT_EQ(c.points.blocks, 8);
  EXPECT_EQ(c.points.corner_covariance, corners.points.corner_covariance);

  const std::string head = std::string(kValid) + "    corners: {camera: {K: [600, 0, 320, 0, 600, 240, 0, 0, 1]}, ";
  expect_parse_error(head + "object: [0, 0, 0, 1, 0], image: [1, 2]}\n", ErrorCode::WrongLength, "samples[0].corners");
  expect_parse_error(head + "object: [0, 0, 0, 1, 0, 0], image: [1, 2, 3, 4], block: 8}\n", ErrorCode::WrongLength,
                     "corners.block");
  expect_parse_error(head + "object: [0, 0, 0], image: [1, 2], covariance: [1, 0, 0]}\n", ErrorCode::WrongLength,
                     "corners.covariance");
  expect_parse_error(head + "object: [0, 0, .nan], image: [1, 2]}\n", ErrorCode::NonFinite, "corners.object[2]");
  const SampleSet plain = io::parse_samples(head + "object: [0, 0, 0], image: [1, 2]}\n", "test.yaml");
  ASSERT_TRUE(plain.samples[0].corners);
  EXPECT_EQ(plain.samples[0].corners->points.corner_covariance.size(), 0);  // independent corners
}

TEST(YamlIo, ANoiseEntryIsEitherTheBlocksOrTheFullPoseCovariance) {
  std::string identity36 = "[";
  for (int i = 0; i < 36; ++i) identity36 += std::string(i ? ", " : "") + (i % 7 == 0 ? "1e-6" : "0");
  identity36 += "]";
  const std::string both = std::string(kValid) + "noise:\n  effector: {rotation: [1e-6, 0, 0, 0, 1e-6, 0, 0, 0, 1e-6], "
                           "translation: [1e-6, 0, 0, 0, 1e-6, 0, 0, 0, 1e-6]}\n  pattern: {pose: " + identity36 +
                           ", rotation: [1e-6, 0, 0, 0, 1e-6, 0, 0, 0, 1e-6]}\n";
  expect_parse_error(both, ErrorCode::MalformedFile, "noise.pattern");
  std::string full = both;
  full.replace(full.find(", rotation: [1e-6, 0, 0, 0, 1e-6, 0, 0, 0, 1e-6]}\n", full.find("pattern: {pose")),
               std::string(", rotation: [1e-6, 0, 0, 0, 1e-6, 0, 0, 0, 1e-6]}\n").size(), "}\n");
  const SampleSet set = io::parse_samples(full, "memory");
  ASSERT_TRUE(set.noise);
  EXPECT_EQ(set.noise->camera.translation, 1e-6 * Eigen::Matrix3d::Identity());
  EXPECT_EQ(set.noise->camera.rotation, 1e-6 * Eigen::Matrix3d::Identity());
}

TEST(YamlIo, MotionsRoundTripExactly) {
  Rng rng(2);
  const MotionSet set = simulate_motions(rng, random_pose(rng, 0.5), 5, paper_noise(1e-4));
  const MotionSet back = io::parse_motions(io::format_motions(set), "memory");
  ASSERT_EQ(back.motions.size(), 5u);
  for (std::size_t i = 0; i < 5; ++i) {
    expect_same_pose(back.motions[i].A, set.motions[i].A);
    expect_same_pose(back.motions[i].B, set.motions[i].B);
  }
  EXPECT_EQ(back.noise->robot.rotation, set.noise->robot.rotation);
}

TEST(YamlIo, AJointResultHasThePatternPoseAndTheCrossCovariance) {
  Rng rng(3);
  const SimulatedSession s = simulate_session(rng, Setup::EyeInHand, typical_X(Setup::EyeInHand), 12, paper_noise(1e-5));
  const Calibration c = solve_joint(s.samples);
  const YAML::Node root = YAML::Load(io::format_result(c, io::context_of(s.samples)));
  EXPECT_EQ(root["method"].as<std::string>(), "joint");
  EXPECT_EQ(root["pattern"]["parent"].as<std::string>(), "base_link");
  EXPECT_EQ(root["pattern"]["child"].as<std::string>(), "tag_0");
  EXPECT_NEAR(root["pattern"]["translation"][0].as<double>(), c.pattern->pose.translation().x(), 1e-15);
  ASSERT_EQ(root["pattern"]["covariance"]["pose"].size(), 36u);
  EXPECT_EQ(root["pattern"]["covariance"]["pose"][7].as<double>(), c.pattern->covariance(1, 1));
  ASSERT_EQ(root["cross_covariance"].size(), 36u);
  EXPECT_EQ(root["cross_covariance"][5].as<double>(), c.cross_covariance(0, 5));  // row-major: (x of X, rz of Y)
  EXPECT_EQ(root["cross_covariance"][30].as<double>(), c.cross_covariance(5, 0));
}

TEST(YamlIo, ResultFileHasTheDocumentedLayout) {
  Rng rng(3);
  const SimulatedSession s = simulate_session(rng, Setup::EyeInHand, typical_X(Setup::EyeInHand), 12, paper_noise(1e-5));
  const Calibration c = solve(s.samples);
  const std::string text = io::format_result(c, io::context_of(s.samples));
  const YAML::Node root = YAML::Load(text);
  EXPECT_EQ(root["setup"].as<std::string>(), "eye_in_hand");
  EXPECT_EQ(root["parent"].as<std::string>(), "tool0");
  EXPECT_EQ(root["child"].as<std::string>(), "camera_optical_frame");
  EXPECT_EQ(root["covariance"]["rotation"].size(), 9u);
  EXPECT_EQ(root["covariance"]["translation"].size(), 9u);
  EXPECT_EQ(root["covariance"]["pose"].size(), 36u);
  EXPECT_EQ(root["samples_used"].as<int>(), 12);
  EXPECT_NEAR(root["transformation"]["x"].as<double>(), c.T_parent_camera.translation().x(), 1e-15);
  // Row-major: entry 1 of `pose` is (x, y); entry 5 is (x, rz), the R-t cross block.
  EXPECT_EQ(root["covariance"]["pose"][1].as<double>(), c.pose_covariance(0, 1));
  EXPECT_EQ(root["covariance"]["pose"][5].as<double>(), c.pose_covariance(0, 5));
  EXPECT_EQ(root["covariance"]["pose"][30].as<double>(), c.pose_covariance(5, 0));
  EXPECT_EQ(root["noise"]["origin"].as<std::string>(), "given");

  const io::CalibrationFile back = io::parse_result(text, "memory");
  expect_same_pose(back.T_parent_camera().pose, c.T_parent_camera);
  EXPECT_EQ(back.T_parent_camera().covariance, c.pose_covariance);
  EXPECT_EQ(back.context.parent, "tool0");
}

TEST(YamlIo, ValidMinimalFileParses) {
  const SampleSet set = io::parse_samples(kValid, "test.yaml");
  EXPECT_EQ(set.samples.size(), 1u);
  EXPECT_FALSE(set.noise.has_value());
  EXPECT_NEAR(set.samples[0].T_camera_pattern.linear()(1, 1), -1.0, 1e-15);
}

TEST(YamlIo, NamedErrorsSayWhereAndHowToFix) {
  expect_parse_error("setup: eye_in_hand\nsamples: [\n", ErrorCode::MalformedFile, "test.yaml:");
  expect_parse_error("samples: []\n", ErrorCode::MissingKey, "setup");
  expect_parse_error("setup: eye_on_hand\nsamples: []\n", ErrorCode::MalformedFile, "eye_on_hand");
  expect_parse_error("setup: eye_in_hand\n", ErrorCode::MissingKey, "samples");
  std::string text = kValid;
  expect_parse_error(text.replace(text.find("[0.1, 0.2, 0.3]"), 15, "[0.1, 0.2]"), ErrorCode::WrongLength,
                     "samples[0].effector.translation");
  text = kValid;
  expect_parse_error(text.replace(text.find("0.2, 0.3"), 3, ".nan"), ErrorCode::NonFinite,
                     "samples[0].effector.translation[1]");
  text = kValid;
  expect_parse_error(text.replace(text.find("[1, 0, 0, 0]"), 12, "[1.5, 0, 0, 0]"), ErrorCode::QuaternionNotUnit,
                     "samples[0].pattern.rotation");
  text = kValid;
  expect_parse_error(text.replace(text.find("0.5]"), 3, "abc"), ErrorCode::MalformedFile, "expected a number");
  text = kValid;
  expect_parse_error(text.replace(text.find("    pattern"), 57, ""), ErrorCode::MissingKey, "pattern");
  // Found by fuzz_yaml_parse: a frame name that is not a name escaped as a yaml-cpp exception.
  expect_parse_error("setup: eye_in_hand\nframes: {base: base_link, pattern: {a: b}}\nsamples: []\n",
                     ErrorCode::MalformedFile, "frames.pattern");
  expect_parse_error(std::string(kValid) + "noise: {effector: {rotation: [1,0,0,0,1,0,0,0,1]}}\n",
                     ErrorCode::MissingKey, "noise.effector");
  expect_parse_error(std::string(kValid) +
                         "noise:\n  effector: {rotation: [-1,0,0,0,1,0,0,0,1], translation: [1,0,0,0,1,0,0,0,1]}\n"
                         "  pattern: {rotation: [1,0,0,0,1,0,0,0,1], translation: [1,0,0,0,1,0,0,0,1]}\n",
                     ErrorCode::InvalidNoise, "noise.effector.rotation");
}

std::string with_effector_matrix(const std::string& numbers) {
  std::string text = kValid;
  const std::string quaternion_form = "{translation: [0.1, 0.2, 0.3], rotation: [0, 0, 0, 1]}";
  return text.replace(text.find(quaternion_form), quaternion_form.size(), "{matrix: [" + numbers + "]}");
}

TEST(YamlIo, PoseAsAMatrixIsTheSamePoseAndBadRotationsAreRefused) {
  // A rotation of 30 deg about z, printed with 6 decimals as exported by a controller.
  const Isometry3d expected = se3::make_pose(so3::exp(Eigen::Vector3d(0, 0, M_PI / 6)), Eigen::Vector3d(0.1, 0.2, 0.3));
  const std::string rounded = "0.866025, -0.5, 0, 0.1,  0.5, 0.866025, 0, 0.2,  0, 0, 1, 0.3,  0, 0, 0, 1";
  const Isometry3d read = io::parse_samples(with_effector_matrix(rounded), "test.yaml").samples[0].T_base_effector;
  EXPECT_LT((read.matrix() - expected.matrix()).norm(), 1e-6);
  EXPECT_LT((read.linear().transpose() * read.linear() - Eigen::Matrix3d::Identity()).norm(), 1e-14);  // projected
  // Sheared (a scale error of 1%), a reflection, a missing last row, too few numbers.
  expect_parse_error(with_effector_matrix("1.01, 0, 0, 0.1,  0, 1, 0, 0.2,  0, 0, 1, 0.3,  0, 0, 0, 1"),
                     ErrorCode::RotationNotOrthonormal, "samples[0].effector.matrix");
  expect_parse_error(with_effector_matrix("-1, 0, 0, 0.1,  0, 1, 0, 0.2,  0, 0, 1, 0.3,  0, 0, 0, 1"),
                     ErrorCode::RotationNotOrthonormal, "det = -1");
  expect_parse_error(with_effector_matrix("1, 0, 0, 0.1,  0, 1, 0, 0.2,  0, 0, 1, 0.3,  0.1, 0.2, 0.3, 1"),
                     ErrorCode::MalformedFile, "0 0 0 1");
  expect_parse_error(with_effector_matrix("1, 0, 0,  0, 1, 0,  0, 0, 1"), ErrorCode::WrongLength, "expected 16");
}

TEST(YamlIo, ARobotPoseFileIsReadInEveryFormatUsersKeep) {
  const Isometry3d pose = se3::make_pose(so3::exp(Eigen::Vector3d(0.3, -1.2, 2.0)), Eigen::Vector3d(0.72, -0.03, 0.41));
  const Eigen::Quaterniond q(pose.linear());
  const Eigen::Vector3d tu = so3::log(pose.linear());
  const Eigen::Matrix4d m = pose.matrix();
  std::string yaml_matrix = "matrix: [", plain, csv;
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) {
      const std::string v = number_text(m(r, c), 17);
      yaml_matrix += v + (r == 3 && c == 3 ? "]" : ", ");
      plain += v + (c == 3 ? "\n" : " ");
      csv += v + (c == 3 ? "\n" : ",");
    }
  }
  const std::string t = number_text(pose.translation().x(), 17) + ", " + number_text(pose.translation().y(), 17) + ", " +
                        number_text(pose.translation().z(), 17);
  const std::string quaternion = "translation: [" + t + "]\nrotation: [" + number_text(q.x(), 17) + ", " +
                                 number_text(q.y(), 17) + ", " + number_text(q.z(), 17) + ", " + number_text(q.w(), 17) + "]\n";
  const std::string json = "{\"translation\": [" + t + "], \"rotation\": [" + number_text(q.x(), 17) + ", " +
                           number_text(q.y(), 17) + ", " + number_text(q.z(), 17) + ", " + number_text(q.w(), 17) + "]}";
  // ViSP's vpPoseVector, as franka_pose_rPe_<i>.yaml holds it.
  const std::string visp = "rows: 6\ncols: 1\ndata:\n  - [" + number_text(pose.translation().x(), 17) + "]\n  - [" +
                           number_text(pose.translation().y(), 17) + "]\n  - [" + number_text(pose.translation().z(), 17) +
                           "]\n  - [" + number_text(tu.x(), 17) + "]\n  - [" + number_text(tu.y(), 17) + "]\n  - [" +
                           number_text(tu.z(), 17) + "]\n";
  for (const std::string& text : {yaml_matrix, plain, csv, quaternion, json, visp}) {
    EXPECT_LE((io::parse_robot_pose(text, "pose.txt").matrix() - m).norm(), 1e-12) << text;
  }
  const auto refused = [](const std::string& text, ErrorCode code, const std::string& what) {
    try {
      io::parse_robot_pose(text, "pose.yaml");
      ADD_FAILURE() << "accepted: " << text;
    } catch (const HandEyeError& e) {
      EXPECT_EQ(e.code(), code) << e.what();
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("pose.yaml"), std::string::npos) << e.what();
    }
  };
  refused("1 0 0 0.1\n0 1 0 0.2\n0 0 1 0.3\n", ErrorCode::WrongLength, "16 numbers");
  refused("1 0 0 0.1\n0 1 0 0.2\n0 0 2 0.3\n0 0 0 1\n", ErrorCode::RotationNotOrthonormal, "not a rotation");
  refused("rows: 6\ncols: 1\ndata: [[0.1], [0.2], [0.3], [0.0], [0.1]]\n", ErrorCode::WrongLength, "6 rows");
  refused("data: [[0.1], [0.2], [.nan], [0.0], [0.1], [0.2]]\n", ErrorCode::NonFinite, "NaN");
  refused("data: [[0.1], [0.2], [x], [0.0], [0.1], [0.2]]\n", ErrorCode::MalformedFile, "number");
  refused("[1, 2, 3]", ErrorCode::MalformedFile, "not a YAML mapping");
}

TEST(YamlIo, ReadInputTellsSamplesFromMotions) {
  const std::string dir = test::scratch_directory();
  io::write_file_atomically(dir + "/s.yaml", kValid);
  EXPECT_TRUE(std::holds_alternative<SampleSet>(io::read_input(dir + "/s.yaml")));
  Rng rng(4);
  io::write_file_atomically(dir + "/m.yaml", io::format_motions(simulate_motions(rng, Isometry3d::Identity(), 3, paper_noise(1e-6))));
  EXPECT_TRUE(std::holds_alternative<MotionSet>(io::read_input(dir + "/m.yaml")));
  io::write_file_atomically(dir + "/x.yaml", "foo: 1\n");
  EXPECT_THROW(io::read_input(dir + "/x.yaml"), HandEyeError);
  try {
    io::read_input(dir + "/does_not_exist.yaml");
    ADD_FAILURE();
  } catch (const HandEyeError& e) {
    EXPECT_EQ(e.code(), ErrorCode::IoError);
  }
}

TEST(YamlIo, AtomicWriteLeavesNoTemporaryAndCreatesDirectories) {
  const std::string dir = ::testing::TempDir() + "/atomic/nested";
  std::filesystem::remove_all(::testing::TempDir() + "/atomic");
  io::write_file_atomically(dir + "/out.yaml", "a: 1\n");
  io::write_file_atomically(dir + "/out.yaml", "a: 2\n");
  EXPECT_EQ(io::read_file(dir + "/out.yaml"), "a: 2\n");
  int files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) files += entry.is_regular_file() ? 1 : 0;
  EXPECT_EQ(files, 1);
}


// What publish.launch and the calibration node read back at start-up.
TEST(YamlIo, AStoredCalibrationIsOursOrEasyHandeyesInBothItsFormats) {
  PoseWithCovariance X;
  X.pose = se3::exp((Vector6d() << 0.03, -0.06, 0.1, 0.4, -0.2, 1.3).finished());
  X.covariance = 1e-6 * Matrix6d::Identity();
  X.covariance(0, 4) = X.covariance(4, 0) = 2e-7;
  io::ResultContext context;
  context.setup = Setup::EyeToHand;
  context.parent = "base_link";
  context.child = "camera_link";
  // Ours carries easy_handeye's `transformation` block too; its covariance decides.
  const io::StoredCalibration ours = io::parse_stored_calibration(io::format_pose_file(X, context), "ours.yaml");
  EXPECT_EQ(ours.format, "handeye_covariance");
  EXPECT_TRUE(ours.has_covariance);
  EXPECT_EQ(ours.setup, Setup::EyeToHand);
  EXPECT_EQ(ours.parent, "base_link");
  EXPECT_EQ(ours.child, "camera_link");
  EXPECT_LE((ours.T_parent_camera.pose.matrix() - X.pose.matrix()).norm(), 1e-15);
  EXPECT_EQ(ours.T_parent_camera.covariance, X.covariance);

  const std::string transformation = test::easy_handeye_transformation(X.pose);
  const std::string nested = test::easy_handeye_text(X.pose, true, "tool0", "camera_color_optical_frame", true);
  const std::string flat = test::easy_handeye_text(X.pose, false, "world", "camera_link", false);
  const io::StoredCalibration a = io::parse_stored_calibration(nested, "easy.yaml");
  EXPECT_EQ(a.format, "easy_handeye");
  EXPECT_FALSE(a.has_covariance);
  EXPECT_EQ(a.setup, Setup::EyeInHand);
  EXPECT_EQ(a.parent, "tool0");
  EXPECT_EQ(a.child, "camera_color_optical_frame");
  EXPECT_LE((a.T_parent_camera.pose.matrix() - X.pose.matrix()).norm(), 1e-15);
  EXPECT_TRUE(a.T_parent_camera.covariance.isZero());
  const io::StoredCalibration b = io::parse_stored_calibration(flat, "easy_old.yaml");
  EXPECT_EQ(b.setup, Setup::EyeToHand);
  EXPECT_EQ(b.parent, "world");
  EXPECT_EQ(b.child, "camera_link");

  const auto expect_error = [](const std::string& text, ErrorCode code, const std::string& mentions) {
    try {
      io::parse_stored_calibration(text, "stored.yaml");
      ADD_FAILURE() << "expected " << to_string(code) << " for\n" << text;
    } catch (const HandEyeError& e) {
      EXPECT_EQ(e.code(), code) << e.what();
      EXPECT_NE(std::string(e.what()).find(mentions), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("Fix:"), std::string::npos) << e.what();
    }
  };
  expect_error(transformation, ErrorCode::MissingKey, "eye_on_hand");
  expect_error("eye_on_hand: maybe\n" + transformation, ErrorCode::MalformedFile, "eye_on_hand");
  expect_error("eye_on_hand: true\ntransformation: {x: 0, y: 0, z: 0, qx: 0, qy: 0, qz: 0, qw: 2}\n",
               ErrorCode::QuaternionNotUnit, "transformation");
  expect_error("eye_on_hand: true\ntransformation: {x: 0, y: 0, qx: 0, qy: 0, qz: 0, qw: 1}\n", ErrorCode::MissingKey,
               "`z`");
  expect_error("parent: tool0\n", ErrorCode::MissingKey, "neither a handeye_covariance result");
  expect_error("eye_on_hand: true\ntransformation: {x: .inf, y: 0, z: 0, qx: 0, qy: 0, qz: 0, qw: 1}\n",
               ErrorCode::NonFinite, "transformation.x");
}

TEST(YamlIo, AHomeRelativePathIsExpanded) {
  const std::string home = std::getenv("HOME") ? std::getenv("HOME") : ".";
  EXPECT_EQ(io::expand_home("~/.ros/x.yaml"), home + "/.ros/x.yaml");
  EXPECT_EQ(io::expand_home("/tmp/~/x.yaml"), "/tmp/~/x.yaml");
  EXPECT_EQ(io::expand_home("~user/x.yaml"), "~user/x.yaml");
}

/// The one guard of the three checks (handeye check, handeye images check, the node): a saved
/// calibration of another setup or other frames than the views' is refused, naming both;
/// what either side does not say agrees.
TEST(YamlIo, ACalibrationIsCheckedOnlyWithViewsOfItsOwnRig) {
  const std::string path = test::scratch_directory() + "/to_check.yaml";
  io::ResultContext context;
  context.setup = Setup::EyeInHand;
  context.parent = "tool0";
  context.child = "camera_optical_frame";
  PoseWithCovariance X;
  X.covariance = 1e-6 * Matrix6d::Identity();
  io::write_file_atomically(path, io::format_pose_file(X, context));
  Rig rig;
  rig.setup = Setup::EyeInHand;
  rig.frames = {"base_link", "tool0", "camera_optical_frame", "board"};
  EXPECT_NO_THROW(io::read_calibration_to_check(path, rig));
  Rig unnamed = rig;
  unnamed.frames = {};
  EXPECT_NO_THROW(io::read_calibration_to_check(path, unnamed)) << "views that do not name their frames agree";
  Rig flange = rig;
  flange.frames.effector = "flange";
  Rig eye_to_hand = rig;
  eye_to_hand.setup = Setup::EyeToHand;
  for (const Rig& other : {flange, eye_to_hand}) {
    try {
      io::read_calibration_to_check(path, other);
      ADD_FAILURE() << "a calibration of another rig was taken";
    } catch (const HandEyeError& e) {
      EXPECT_EQ(e.code(), ErrorCode::MalformedFile);
      EXPECT_NE(std::string(e.what()).find("T_tool0_camera_optical_frame (eye_in_hand)"), std::string::npos) << e.what();
    }
  }
}

/// Every section of a result: its description names each of its fields, and it reads back
/// as written. A field added to a struct but not to its `fields` fails the first.
template <class S>
void expect_described_and_round_trips(const char* name, const std::function<void(S&)>& widest = {}) {
  const S probe{};
  EXPECT_EQ(test::undescribed(probe), std::vector<std::string>{}) << name;
  S written = test::filled<S>();
  if (widest) widest(written);  // the state in which it writes the most
  YAML::Emitter out;
  io::detail::new_emitter(out);
  io::detail::emit_section(out, written, false);
  S read{};
  io::detail::read_section(YAML::Load(out.c_str()), io::detail::Location{name, ""}, read);
  EXPECT_EQ(test::flattened(read), test::flattened(written)) << name << ":\n" << out.c_str();
}

TEST(Sections, EachIsDescribedWholeAndReadsBackAsWritten) {
  expect_described_and_round_trips<Calibration::NoiseComponent>("noise component");
  expect_described_and_round_trips<Calibration::NoiseCandidate>("noise candidate");
  expect_described_and_round_trips<Calibration::ResidualCheck>("residual check");
  expect_described_and_round_trips<Calibration::Rejected>("rejected");
  expect_described_and_round_trips<Calibration::Prediction>("prediction");
  expect_described_and_round_trips<Calibration::CornerFit::Image>("corner image");
  expect_described_and_round_trips<Calibration::ResidualNoise>("residual noise");
  expect_described_and_round_trips<Calibration::Honesty>("honesty");
  expect_described_and_round_trips<Calibration::Honesty::Reference>("honesty reference");
  expect_described_and_round_trips<Calibration::Honesty::Runs>("honesty runs");
  expect_described_and_round_trips<Calibration::SharedError>("shared robot error",
                                                             [](Calibration::SharedError& e) { e.not_fitted.clear(); });
  expect_described_and_round_trips<Calibration::SharedError>("shared robot error, not fitted");
  expect_described_and_round_trips<Calibration::SharedError::View>("shared robot error view");
  expect_described_and_round_trips<Calibration::CornerFit>("corner fit");
  expect_described_and_round_trips<Calibration::CornerFit>("corner fit, intrinsics kept",
                                                           [](Calibration::CornerFit& f) { f.intrinsics.reset(); });
  EXPECT_EQ(test::undescribed(StageDiagnostics{}), std::vector<std::string>{});  // written, not read
}

/// The guard itself: a struct with a field its description leaves out is caught.
struct Undescribed {
  double a = 0.0;
  bool forgotten = false;
  double b = 0.0;
  template <class Self, class Visit>
  static void fields(Self& s, Visit&& visit) {
    visit("a", s.a);
    visit("b", s.b);
  }
};
struct UndescribedAtTheEnd {
  double a = 0.0;
  int forgotten = 0;
  template <class Self, class Visit>
  static void fields(Self& s, Visit&& visit) {
    visit("a", s.a);
  }
};
TEST(Sections, AFieldLeftOutOfItsDescriptionIsFound) {
  EXPECT_EQ(test::undescribed(Undescribed{}).size(), 1u);
  EXPECT_EQ(test::undescribed(UndescribedAtTheEnd{}).size(), 1u);
  EXPECT_EQ(test::undescribed(Calibration::Prediction{}), std::vector<std::string>{});
}

}  // namespace
}  // namespace handeye
