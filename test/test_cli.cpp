// Runs the real `handeye` binary as a user would and checks output and exit codes.
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <cmath>
#include <filesystem>
#include <sstream>
#include <sys/wait.h>

#include <yaml-cpp/yaml.h>

#include "handeye_covariance/core/object_pose.h"
#include "handeye_covariance/io/yaml_io.h"
#include "cli_helpers.h"

namespace {

using handeye::test::CliRun;
using handeye::test::run;
using handeye::test::temp;

TEST(Cli, HelpListsTheSubcommands) {
  const CliRun r = run("--help");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.out.find("solve"), std::string::npos);
  EXPECT_NE(r.out.find("sim"), std::string::npos);
  EXPECT_NE(r.out.find("bag"), std::string::npos);
  // Every command name stands apart from its summary (a fixed width once printed "validateMonte-Carlo").
  for (const char* name : {"solve", "sim", "bag", "compose", "noise", "suggest", "validate", "target"}) {
    EXPECT_NE(r.out.find("  " + std::string(name) + "  "), std::string::npos) << name << " in\n" << r.out;
  }
  EXPECT_EQ(run("solve --help").exit_code, 0);
  EXPECT_NE(run("solve --help").out.find("--input"), std::string::npos);
}

TEST(Cli, SimThenSolveRecoversTheTruthWithin3Sigma) {
  const std::string samples = temp("samples.yaml"), truth = temp("truth.yaml"), result = temp("result.yaml");
  ASSERT_EQ(run("sim --output " + samples + " --truth " + truth + " --samples 25 --seed 3").exit_code, 0);
  const CliRun r = run("solve --input " + samples + " --output " + result);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("1 sigma [mm]"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("1 sigma [deg]"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("T_tool0_camera_optical_frame"), std::string::npos) << r.out;
  const auto estimate = handeye::io::read_result(result);
  const auto exact = handeye::io::read_result(truth);
  const Eigen::Vector3d error = estimate.T_parent_camera().pose.translation() - exact.T_parent_camera().pose.translation();
  const Eigen::Matrix3d covariance = estimate.T_parent_camera().covariance.topLeftCorner<3, 3>();
  const double mahalanobis = std::sqrt(error.dot(covariance.inverse() * error));
  EXPECT_LT(mahalanobis, 3.0 * std::sqrt(3.0));
  EXPECT_GT(covariance.trace(), 0.0);
}

TEST(Cli, EstimatedNoiseIsAnnounced) {
  const std::string samples = temp("nonoise.yaml"), result = temp("nonoise_result.yaml");
  ASSERT_EQ(run("sim --output " + samples + " --omit-noise-block --samples 20").exit_code, 0);
  const CliRun r = run("solve --input " + samples + " --output " + result);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("ESTIMATED from the residuals"), std::string::npos) << r.out;
  EXPECT_NE(handeye::io::read_file(result).find("estimated_from_residuals"), std::string::npos);
}

// The split-half check a user runs on a session: about 6 on an honest simulated
// one, judged against its own reference (an honest covariance on the same poses);
// a few samples, a motions file and an unknown robust mode are refused.
TEST(Cli, SplitCheckSaysWhetherTheCovarianceIsHonest) {
  const std::string samples = temp("split.yaml"), result = temp("split_result.yaml");
  ASSERT_EQ(run("sim --output " + samples + " --omit-noise-block --samples 60 --seed 3").exit_code, 0);
  const CliRun r = run("solve --input " + samples + " --output " + result + " --split-check 40 --reference-sessions 30");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string verdict = "  honesty check         honest (split-half NEES ";
  const std::size_t at = r.out.find(verdict);
  ASSERT_NE(at, std::string::npos) << r.out;
  const double nees = std::stod(r.out.substr(at + verdict.size()));
  EXPECT_GT(nees, 4.5) << r.out;
  EXPECT_LT(nees, 7.5) << r.out;
  const std::size_t against = r.out.find(" against ", at);
  ASSERT_NE(against, std::string::npos) << r.out;
  const double honest = std::stod(r.out.substr(against + 9));
  EXPECT_GT(honest, 5.0) << r.out;
  EXPECT_LT(honest, 7.5) << r.out;
  EXPECT_NE(r.out.find("40 random splits into halves of 30 (middle 90%); reference: 30 simulated sessions"),
            std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("OVERCONFIDENT"), std::string::npos) << r.out;
  // The result file records the check.
  const YAML::Node written = YAML::LoadFile(result);
  EXPECT_EQ(written["honesty"]["verdict"].as<std::string>(), "honest");
  EXPECT_EQ(written["honesty"]["splits"].as<int>(), 40);
  EXPECT_DOUBLE_EQ(written["honesty"]["inflation"].as<double>(), 1.0);
  EXPECT_FALSE(written["honesty"]["model_covariance"]);

  // The second look, halves of runs of consecutive samples: said, recorded, and left
  // out with the reason beyond n / 4; a negative length is refused.
  EXPECT_NE(r.out.find("the other look: halves of runs of 4 consecutive samples, ratio "), std::string::npos) << r.out;
  EXPECT_EQ(written["honesty"]["runs"]["length"].as<int>(), 4);  // auto: 60 / 8 within [2, 4]
  EXPECT_FALSE(written["honesty"]["run_length"]);                 // random halves decided: not written
  const std::string runs_result = temp("split_runs.yaml");
  const CliRun runs = run("solve --input " + samples + " --output " + runs_result +
                          " --split-check 40 --reference-sessions 30 --split-runs 3");
  ASSERT_EQ(runs.exit_code, 0) << runs.err;
  EXPECT_NE(runs.out.find("halves of runs of 3 consecutive samples"), std::string::npos) << runs.out;
  EXPECT_EQ(YAML::LoadFile(runs_result)["honesty"]["runs"]["length"].as<int>(), 3);
  const CliRun negative = run("solve --input " + samples + " --output " + temp("split_negative.yaml") + " --split-runs -1");
  EXPECT_EQ(negative.exit_code, 2);
  EXPECT_NE(negative.err.find("--split-runs >= 0"), std::string::npos) << negative.err;
  const CliRun long_runs = run("solve --input " + samples + " --output " + temp("split_long.yaml") +
                               " --split-check 40 --reference-sessions 30 --split-runs 16");
  EXPECT_EQ(long_runs.exit_code, 0) << long_runs.err;
  EXPECT_NE(long_runs.out.find("no runs look: halves of runs of 16 consecutive samples need at least 64 samples, there are 60"),
            std::string::npos) << long_runs.out;

  const std::string few = temp("split_few.yaml");
  ASSERT_EQ(run("sim --output " + few + " --samples 6").exit_code, 0);
  const CliRun too_few = run("solve --input " + few + " --output " + temp("split_few_result.yaml") + " --split-check 40");
  EXPECT_EQ(too_few.exit_code, 0) << too_few.err;
  EXPECT_NE(too_few.out.find("honesty check         not run: it needs 8 kept samples (two halves of 4), there are 6"),
            std::string::npos) << too_few.out;
  const CliRun bad_mode = run("solve --input " + samples + " --output " + temp("split_bad.yaml") + " --robust sometimes");
  EXPECT_EQ(bad_mode.exit_code, 2);
  EXPECT_NE(bad_mode.err.find("unknown robust mode `sometimes`"), std::string::npos) << bad_mode.err;
  EXPECT_FALSE(std::filesystem::exists(temp("split_bad.yaml")));
  // The shared robot error's setting: a bad value is refused naming the option; at 60
  // samples (beyond its 40) the model is not fitted, and the summary says why.
  const CliRun bad_shared = run("solve --input " + samples + " --output " + temp("shared_bad.yaml") + " --shared-robot-error yes");
  EXPECT_EQ(bad_shared.exit_code, 2);
  EXPECT_NE(bad_shared.err.find("unknown shared robot error setting `yes`"), std::string::npos) << bad_shared.err;
  EXPECT_NE(bad_shared.err.find("--shared-robot-error"), std::string::npos) << bad_shared.err;
  EXPECT_FALSE(std::filesystem::exists(temp("shared_bad.yaml")));
  EXPECT_NE(r.out.find("shared robot error    not fitted: 60 kept samples; it is fitted from 16 to 40"), std::string::npos)
      << r.out;
  const CliRun shared_off = run("solve --input " + samples + " --output " + temp("shared_off.yaml") +
                                " --split-check 0 --shared-robot-error off");
  EXPECT_EQ(shared_off.exit_code, 0) << shared_off.err;
  EXPECT_EQ(shared_off.out.find("shared robot error"), std::string::npos) << shared_off.out;
}

TEST(Cli, DegenerateInputExits2WithReasonAndWritesNothing) {
  const std::string input = temp("degenerate.yaml"), result = temp("degenerate_result.yaml");
  // Three samples of a robot that only translates.
  handeye::io::write_file_atomically(input, R"(setup: eye_in_hand
samples:
  - {effector: {translation: [0.1, 0, 0.5], rotation: [0, 0, 0, 1]}, pattern: {translation: [0, 0, 0.5], rotation: [1, 0, 0, 0]}}
  - {effector: {translation: [0.2, 0, 0.5], rotation: [0, 0, 0, 1]}, pattern: {translation: [-0.1, 0, 0.5], rotation: [1, 0, 0, 0]}}
  - {effector: {translation: [0.2, 0.1, 0.5], rotation: [0, 0, 0, 1]}, pattern: {translation: [-0.1, 0.1, 0.5], rotation: [1, 0, 0, 0]}}
  - {effector: {translation: [0.1, 0.1, 0.4], rotation: [0, 0, 0, 1]}, pattern: {translation: [0, 0.1, 0.6], rotation: [1, 0, 0, 0]}}
)");
  const CliRun r = run("solve --input " + input + " --output " + result);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("PureTranslation"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(result));
}

TEST(Cli, BadInvocationsExit2) {
  EXPECT_EQ(run("").exit_code, 2);
  EXPECT_EQ(run("frobnicate").exit_code, 2);
  const CliRun missing = run("solve --input /nonexistent/samples.yaml --output " + temp("x.yaml"));
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_NE(missing.err.find("IoError"), std::string::npos) << missing.err;
  const CliRun no_input = run("solve");
  EXPECT_EQ(no_input.exit_code, 2);
  EXPECT_NE(no_input.err.find("input"), std::string::npos) << no_input.err;
}

TEST(Cli, SimBagThenBagReplay) {
  const std::string bag = temp("sim.bag"), truth = temp("sim_truth.yaml"), result = temp("sim_result.yaml"),
                    samples = temp("sim_samples.yaml");
  const CliRun sim = run("sim --output " + bag + " --truth " + truth + " --samples 12 --seed 5");
  ASSERT_EQ(sim.exit_code, 0) << sim.err;
  const CliRun r = run("bag --bag " + bag + " --output " + result + " --samples-out " + samples);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("samples accepted"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("1 sigma [mm]"), std::string::npos) << r.out;
  EXPECT_GE(handeye::io::read_samples(samples).samples.size(), 11u);
  const auto estimate = handeye::io::read_result(result), exact = handeye::io::read_result(truth);
  EXPECT_LT((estimate.T_parent_camera().pose.translation() - exact.T_parent_camera().pose.translation()).norm(), 0.005);
}

TEST(Cli, BadBagsExit2WithTheReasonAndWriteNothing) {
  const std::string bag = temp("sim2.bag"), result = temp("bad_result.yaml");
  ASSERT_EQ(run("sim --output " + bag + " --samples 5").exit_code, 0);
  const std::string config = temp("wrong_topic.yaml");
  handeye::io::write_file_atomically(config, "detections_topic: /nothing_here\n");
  const CliRun wrong_topic = run("bag --bag " + bag + " --config " + config + " --output " + result);
  EXPECT_EQ(wrong_topic.exit_code, 2);
  EXPECT_NE(wrong_topic.err.find("NoData"), std::string::npos) << wrong_topic.err;
  handeye::io::write_file_atomically(config, "detections_topik: /tag_detections\n");
  const CliRun typo = run("bag --bag " + bag + " --config " + config + " --output " + result);
  EXPECT_EQ(typo.exit_code, 2);
  EXPECT_NE(typo.err.find("unknown setting `detections_topik`"), std::string::npos) << typo.err;
  handeye::io::write_file_atomically(temp("garbage.bag"), "garbage");
  const CliRun corrupt = run("bag --bag " + temp("garbage.bag") + " --output " + result);
  EXPECT_EQ(corrupt.exit_code, 2);
  EXPECT_NE(corrupt.err.find("IoError"), std::string::npos) << corrupt.err;
  EXPECT_FALSE(std::filesystem::exists(result));
}

TEST(Cli, ValidateSmokeTestWritesFiniteFiguresAndPlots) {
  const std::string dir = ::testing::TempDir() + "/validate";
  std::filesystem::remove_all(dir);
  const CliRun r = run("validate --protocol paper,pose-stream --lambda 1e-5,1e-4 --M 40 --k 10 --seed 3 --out " + dir);
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  std::istringstream csv(handeye::io::read_file(dir + "/validation.csv"));
  std::string line;
  std::getline(csv, line);  // header
  int rows = 0;
  while (std::getline(csv, line)) {
    ++rows;
    std::istringstream fields(line);
    std::string field;
    std::getline(fields, field, ',');  // protocol
    for (int column = 1; std::getline(fields, field, ','); ++column) {
      EXPECT_TRUE(std::isfinite(std::stod(field))) << "row " << rows << " column " << column << ": " << line;
    }
  }
  EXPECT_EQ(rows, 4);
  for (const char* png : {"fig3_epsilon.png", "fig2_paper.png", "fig2_pose-stream.png"}) {
    EXPECT_GT(std::filesystem::file_size(dir + "/" + png), 10000u) << png;
  }
  EXPECT_EQ(run("validate --protocol nonsense --M 20").exit_code, 2);
}

TEST(Cli, ShippedExampleSolves) {
  const std::string result = temp("example_result.yaml");
  const CliRun r = run(std::string("solve --input ") + HANDEYE_SOURCE_DIR + "/config/examples/eye_in_hand_samples.yaml --output " + result);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto estimate = handeye::io::read_result(result);
  const auto exact = handeye::io::read_result(std::string(HANDEYE_SOURCE_DIR) + "/config/examples/eye_in_hand_truth.yaml");
  EXPECT_LT((estimate.T_parent_camera().pose.translation() - exact.T_parent_camera().pose.translation()).norm(), 0.003);
}

}  // namespace

namespace compose_test {

std::string write(const std::string& name, const std::string& text) {
  const std::string path = temp(name);
  handeye::io::write_file_atomically(path, text);
  return path;
}

TEST(Cli, ComposeGivesTheObjectInTheBaseWithEq68sCovariance) {
  const std::string samples = temp("c_samples.yaml"), result = temp("c_result.yaml"), object = temp("c_object.yaml");
  ASSERT_EQ(run("sim --output " + samples + " --samples 15 --seed 5").exit_code, 0);
  ASSERT_EQ(run("solve --input " + samples + " --output " + result).exit_code, 0);
  // The detection as a pose file with its own covariance; the robot inline with isotropic sigmas.
  const std::string detection = write("c_detection.yaml",
                                      "translation: [0.05, 0.02, 0.7]\nrotation: [0, 0, 0.1, 0.99498743710662]\n"
                                      "covariance: {rotation: [4e-7, 0, 0, 0, 4e-7, 0, 0, 0, 9e-7],"
                                      " translation: [1e-8, 0, 0, 0, 1e-8, 0, 0, 0, 4e-7]}\n");
  const CliRun r = run("compose --calibration " + result + " --object " + detection +
                       " --effector 0.5,0.1,0.6,1,0,0,0 --robot-sigma-mm 0.05 --robot-sigma-deg 0.01"
                       " --point 0.02,0,0 --output " + object);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("T_base_link_object"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("calibration (X)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("point [0.02 0 0]"), std::string::npos) << r.out;

  // The file holds eq. (68) with the three covariances compounded.
  const auto calibration = handeye::io::read_result(result);
  handeye::ObjectPoseInput in;
  in.X = calibration.T_parent_camera();
  in.T_camera_object = handeye::io::read_pose_file(detection).value;
  const double mm = 0.05e-3, rad = 0.01 * M_PI / 180.0;
  in.T_base_effector.pose = Eigen::Isometry3d(Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()));
  in.T_base_effector.pose.translation() = Eigen::Vector3d(0.5, 0.1, 0.6);
  in.T_base_effector.covariance.diagonal() << mm * mm, mm * mm, mm * mm, rad * rad, rad * rad, rad * rad;
  const handeye::ObjectPose expected = handeye::object_in_base(in);
  const handeye::io::PoseFile written = handeye::io::read_pose_file(object);
  EXPECT_EQ(written.parent, "base_link");
  EXPECT_EQ(written.child, "object");
  EXPECT_TRUE(written.value.pose.isApprox(expected.T_base_object.pose, 1e-9));
  EXPECT_TRUE(written.value.covariance.isApprox(expected.T_base_object.covariance, 1e-9));
  // X's part is there: the compounded position variance exceeds robot + detection alone.
  EXPECT_GT((expected.from_calibration.topLeftCorner<3, 3>().trace()), 0.0);
}

TEST(Cli, ComposeRefusesMissingOrBadPosesAndWritesNothing) {
  const std::string samples = temp("c2_samples.yaml"), result = temp("c2_result.yaml"), object = temp("c2_object.yaml");
  ASSERT_EQ(run("sim --output " + samples + " --samples 12 --seed 6").exit_code, 0);
  ASSERT_EQ(run("solve --input " + samples + " --output " + result).exit_code, 0);
  const std::string base = "compose --calibration " + result + " --output " + object + " ";
  struct Case {
    std::string args, expected;
  };
  for (const Case& c : {Case{"--object 0,0,0.7,0,0,0,1", "needs the robot pose"},
                        Case{"--object 0,0,0.7,0,0,0,2 --effector 0,0,0,0,0,0,1", "QuaternionNotUnit"},
                        Case{"--object 0,0,0.7,0,0,1 --effector 0,0,0,0,0,0,1", "expected 7 numbers"},
                        Case{"--object 0,0,0.7,0,0,0,1 --effector 0,0,0,0,0,0,1 --object-sigma-mm 1", "give both"},
                        Case{"--object 0,0,0.7,0,0,0,1 --effector 0,0,0,0,0,0,1 --point 1,2", "a point is x,y,z"},
                        Case{"--object /nonexistent/detection.yaml --effector 0,0,0,0,0,0,1", "IoError"}}) {
    const CliRun r = run(base + c.args);
    EXPECT_EQ(r.exit_code, 2) << c.args;
    EXPECT_NE(r.err.find(c.expected), std::string::npos) << c.args << "\n" << r.err;
    EXPECT_FALSE(std::filesystem::exists(object)) << c.args;
  }
  // Without any covariance for the detection and no noise model to fall back on: refused.
  const std::string truth = temp("c2_truth.yaml");
  ASSERT_EQ(run("sim --output " + temp("c2_s2.yaml") + " --truth " + truth + " --samples 5").exit_code, 0);
  const CliRun r = run("compose --calibration " + truth + " --object 0,0,0.7,0,0,0,1 --effector 0,0,0,0,0,0,1");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("no covariance for the object pose"), std::string::npos) << r.err;
}

}  // namespace compose_test

namespace noise_test {

TEST(Cli, NoiseMeasuresTheSimulatedNoiseAndSolveAcceptsIt) {
  const std::string samples = temp("n_samples.yaml"), noise = temp("n_noise.yaml"), result = temp("n_result.yaml");
  ASSERT_EQ(run("sim --output " + samples + " --samples 400 --seed 12 --pattern-translation-noise-mm 0.3"
                " --pattern-rotation-noise-deg 0.04 --robot-translation-noise-mm 0 --robot-rotation-noise-deg 0")
                .exit_code, 0);
  const CliRun r = run("noise --input " + samples + " --output " + noise);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("Noise from residuals: 400 samples"), std::string::npos) << r.out;
  // The block is what the node's ~noise_config and `solve --noise` read.
  const handeye::MeasurementNoise measured = handeye::io::read_noise_file(noise);
  const double dof = 398.0, band = 4.0 * std::sqrt(2.0 / dof);  // 4 sigma of a variance estimate
  for (int axis = 0; axis < 3; ++axis) {
    EXPECT_NEAR(measured.camera.translation(axis, axis) / std::pow(0.3e-3, 2), 1.0, band) << axis;
    EXPECT_NEAR(measured.camera.rotation(axis, axis) / std::pow(0.04 * M_PI / 180, 2), 1.0, band) << axis;
  }
  const CliRun solved = run("solve --input " + samples + " --noise " + noise + " --output " + result + " --split-check 0");
  ASSERT_EQ(solved.exit_code, 0) << solved.err;
  EXPECT_NE(solved.out.find("noise                 given"), std::string::npos) << solved.out;
}

TEST(Cli, NoiseRefusesWhatItCannotMeasure) {
  const std::string samples = temp("n2_samples.yaml"), noise = temp("n2_noise.yaml");
  ASSERT_EQ(run("sim --output " + samples + " --samples 8 --seed 13").exit_code, 0);
  CliRun r = run("noise --input " + samples + " --source repeated --output " + noise);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("hold the robot still"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(noise));
  r = run("noise --input " + samples + " --source guess --output " + noise);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("unknown source"), std::string::npos) << r.err;
  const std::string hand = temp("n2_hand.yaml"), hand_result = temp("n2_hand_result.yaml");
  ASSERT_EQ(run("sim --output " + hand + " --setup eye_to_hand --samples 8").exit_code, 0);
  ASSERT_EQ(run("solve --input " + hand + " --output " + hand_result).exit_code, 0);
  r = run("noise --input " + samples + " --calibration " + hand_result + " --output " + noise);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("another setup"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(noise));
}

}  // namespace noise_test

namespace suggest_test {

TEST(Cli, SuggestRanksNextPosesAndPlansToTheTarget) {
  const std::string samples = temp("s_samples.yaml"), out = temp("s_out.yaml"), candidates = temp("s_candidates.yaml");
  ASSERT_EQ(run("sim --output " + samples + " --samples 6 --seed 14").exit_code, 0);
  const CliRun r = run("suggest --input " + samples + " --target-mm 0.4 --count 4 --output " + out);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("Next poses, best first"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("To reach 0.4 mm: "), std::string::npos) << r.out;
  const YAML::Node file = YAML::LoadFile(out);
  ASSERT_EQ(file["suggestions"].size(), 4u);
  const double now = file["current_object_sigma_mm"].as<double>();
  double previous = 0.0;
  for (const YAML::Node& s : file["suggestions"]) {
    const double sigma = s["object_sigma_mm"].as<double>();
    EXPECT_LT(sigma, now);
    EXPECT_GE(sigma, previous);  // best first
    previous = sigma;
  }
  EXPECT_TRUE(file["plan"]["reached"].as<bool>());
  const YAML::Node plan = file["plan"]["poses"];
  ASSERT_GT(plan.size(), 0u);
  EXPECT_LE(plan[plan.size() - 1]["object_sigma_mm"].as<double>(), 0.4);

  // The suggestions, fed back as candidates, are ranked the same way.
  std::string text = "candidates:\n";
  for (int i = 3; i >= 0; --i) {  // reversed
    const YAML::Node s = file["suggestions"][i];
    text += "  - {translation: [" + s["translation"][0].as<std::string>() + ", " + s["translation"][1].as<std::string>() +
            ", " + s["translation"][2].as<std::string>() + "], rotation: [" + s["rotation"][0].as<std::string>() + ", " +
            s["rotation"][1].as<std::string>() + ", " + s["rotation"][2].as<std::string>() + ", " +
            s["rotation"][3].as<std::string>() + "]}\n";
  }
  handeye::io::write_file_atomically(candidates, text);
  const std::string again = temp("s_again.yaml");
  ASSERT_EQ(run("suggest --input " + samples + " --candidates " + candidates + " --count 1 --output " + again).exit_code, 0);
  EXPECT_NEAR(YAML::LoadFile(again)["suggestions"][0]["object_sigma_mm"].as<double>(),
              file["suggestions"][0]["object_sigma_mm"].as<double>(), 1e-9);
}

TEST(Cli, SuggestRefusesBadRequests) {
  const std::string samples = temp("s2_samples.yaml"), out = temp("s2_out.yaml"), bad = temp("s2_bad.yaml");
  ASSERT_EQ(run("sim --output " + samples + " --samples 6 --seed 15").exit_code, 0);
  CliRun r = run("suggest --input " + samples + " --criterion trace --output " + out);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("unknown criterion"), std::string::npos) << r.err;
  handeye::io::write_file_atomically(bad, "candidates:\n  - {translation: [0, 0, 0.5], rotation: [0, 0, 0, 3]}\n");
  r = run("suggest --input " + samples + " --candidates " + bad + " --output " + out);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("candidates[0].rotation"), std::string::npos) << r.err;
  r = run("suggest --input " + samples + " --reach-mm 0.001 --output " + out);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("widen the reach"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(out));
}

}  // namespace suggest_test

namespace outlier_test {

TEST(Cli, SolveRejectsAWrongDetectionAndReportsIt) {
  const std::string samples = temp("o_samples.yaml"), corrupted = temp("o_corrupted.yaml"), result = temp("o_result.yaml");
  ASSERT_EQ(run("sim --output " + samples + " --samples 20 --seed 16").exit_code, 0);
  handeye::SampleSet set = handeye::io::read_samples(samples);
  set.samples[7].T_camera_pattern = set.samples[4].T_camera_pattern;  // paired with the wrong robot pose
  handeye::io::write_file_atomically(corrupted, handeye::io::format_samples(set));
  const CliRun r = run("solve --input " + corrupted + " --output " + result);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("rejected samples[7]:"), std::string::npos) << r.out;
  const YAML::Node file = YAML::LoadFile(result);
  ASSERT_EQ(file["rejected"].size(), 1u);
  EXPECT_EQ(file["rejected"][0]["index"].as<int>(), 7);
  EXPECT_EQ(file["samples_used"].as<int>(), 19);
  // Without rejection the estimator refuses the set (the motion angles disagree).
  const CliRun kept = run("solve --keep-outliers --input " + corrupted + " --output " + temp("o_kept.yaml"));
  EXPECT_EQ(kept.exit_code, 2);
  EXPECT_NE(kept.err.find("AngleMismatch"), std::string::npos) << kept.err;
}

}  // namespace outlier_test

namespace layers_test {

/// The shared libraries `ldd` lists for a binary.
std::string linked_libraries(const std::string& binary) {
  const std::string out = ::testing::TempDir() + "/ldd_out";
  EXPECT_EQ(std::system(("ldd " + binary + " >" + out).c_str()), 0) << binary;
  return handeye::io::read_file(out);
}

// `handeye solve/noise/compose/suggest/validate/sim` link no ROS library: the bag
// commands are handeye_bag, which `handeye bag` runs. The rviz plugin links the
// core and the ROS bridge, not the vision library's OpenCV or libapriltag.
// docs/checking.md's "Offline (handeye check)", as typed: a calibration, 5 later views
// (exit 0, consistent), 5 views after the camera moved 3 mm on its mount (exit 3, X
// changed, by about 3 mm), the check file; and what it refuses.
TEST(Cli, CheckSaysWhetherACalibrationStillHolds) {
  const std::string session = temp("check_session.yaml"), calibration = temp("check_calibration.yaml"),
                    later = temp("check_later.yaml"), bumped = temp("check_bumped.yaml"), out = temp("check.yaml");
  ASSERT_EQ(run("sim --output " + session + " --samples 20 --seed 1").exit_code, 0);
  ASSERT_EQ(run("solve --input " + session + " --output " + calibration).exit_code, 0);
  ASSERT_EQ(run("sim --output " + later + " --samples 5 --seed 2").exit_code, 0);
  const CliRun same = run("check --calibration " + calibration + " --input " + later);
  EXPECT_EQ(same.exit_code, 0) << same.out << same.err;
  EXPECT_NE(same.out.find("consistent (p = "), std::string::npos) << same.out;
  ASSERT_EQ(run("sim --output " + bumped + " --samples 5 --seed 2 --camera-moved-mm 3").exit_code, 0);
  const CliRun moved = run("check --calibration " + calibration + " --input " + bumped + " --output " + out);
  EXPECT_EQ(moved.exit_code, 3) << moved.out << moved.err;
  EXPECT_NE(moved.out.find("X changed (p "), std::string::npos) << moved.out;
  const YAML::Node check = YAML::LoadFile(out);
  EXPECT_EQ(check["verdict"].as<std::string>(), "changed");
  EXPECT_EQ(check["changed"].as<std::string>(), "X");
  EXPECT_LT(check["p_value"].as<double>(), 0.01);
  ASSERT_EQ(check["change"].size(), 6u);
  ASSERT_EQ(check["change_covariance"].size(), 36u);
  const Eigen::Vector3d t(check["change"][0].as<double>(), check["change"][1].as<double>(), check["change"][2].as<double>());
  const double sigma = std::sqrt(check["change_covariance"][0].as<double>() + check["change_covariance"][7].as<double>() +
                                 check["change_covariance"][14].as<double>());
  EXPECT_NEAR(t.norm(), 3e-3, 3.0 * sigma);  // the 3 mm move, within the check's own 3 sigma
  EXPECT_EQ(check["views"].size(), 5u);

  // A pose file without Y or a noise model, and no views: refused with the reason, exit 2.
  const std::string truth = temp("check_truth.yaml");
  ASSERT_EQ(run("sim --output " + temp("check_t.yaml") + " --samples 5 --truth " + truth).exit_code, 0);
  const CliRun old = run("check --calibration " + truth + " --input " + later);
  EXPECT_EQ(old.exit_code, 2);
  EXPECT_NE(old.err.find("noise model"), std::string::npos) << old.err;
  const CliRun nothing = run("check --calibration " + calibration);
  EXPECT_EQ(nothing.exit_code, 2);
  EXPECT_NE(nothing.err.find("--input"), std::string::npos) << nothing.err;
}

TEST(Layers, HandeyeLinksNoRosLibraryAndTheRvizPluginNoOpenCv) {
  const std::string handeye = linked_libraries(HANDEYE_CLI);
  for (const char* library : {"libroscpp", "librosbag", "libtf2", "libcv_bridge", "librostime", "libopencv", "libapriltag",
                              "libcairo"}) {
    EXPECT_EQ(handeye.find(library), std::string::npos) << "handeye links " << library << ":\n" << handeye;
  }
  EXPECT_NE(handeye.find("libyaml-cpp"), std::string::npos) << "ldd printed no libraries?\n" << handeye;
  const std::string plugin = linked_libraries(HANDEYE_RVIZ_PLUGIN);
  for (const char* library : {"libopencv", "libapriltag", "librosbag"}) {
    EXPECT_EQ(plugin.find(library), std::string::npos) << "the rviz plugin links " << library << ":\n" << plugin;
  }
  EXPECT_NE(plugin.find("librviz"), std::string::npos) << plugin;
  // ... and the bag commands still work through it.
  const handeye::test::CliRun bag = handeye::test::run("bag --help");
  EXPECT_EQ(bag.exit_code, 0) << bag.err;
  EXPECT_NE(bag.out.find("--samples-out"), std::string::npos) << bag.out;
}

}  // namespace layers_test
