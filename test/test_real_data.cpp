// Real data is the judge: the real Franka + RealSense sessions of
// ../shared/realdata/visp-franka (its README), read from there, never copied.
//
// The eye-to-hand AprilTag session, run the way the node runs it: the AprilTag
// detector with its edge-fit covariance and its pooled pixel sigma, each sample
// with its own detection covariance, no noise config, outlier rejection on
// (CalibrationSession, as the node, handeye bag and handeye solve use it). The
// published X is ViSP's estimate from the same 8 images, not the truth; with 8
// poses it is weakly determined, so X is judged in units of the combined
// uncertainty: ours, and the leave-one-out (jackknife) spread of the same
// pipeline for theirs.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sys/wait.h>
#include <yaml-cpp/yaml.h>
#include <functional>
#include <map>
#include <numeric>
#include <random>
#include <stdexcept>

#include "handeye_covariance/core/statistics.h"
#include "handeye_covariance/core/targets/markers.h"
#include "handeye_covariance/estimation/calibration_check.h"
#include "handeye_covariance/estimation/shared_robot_error.h"
#include "handeye_covariance/estimation/split_check.h"
#include "handeye_covariance/io/noise_text.h"
#include "handeye_covariance/io/result_file.h"
#include "handeye_covariance/io/summary.h"
#include "handeye_covariance/session/report.h"
#include "handeye_covariance/corners/corner_calibration.h"
#include "scratch_directory.h"
#include "test_helpers.h"
#include "handeye_covariance/io/yaml_io.h"
#include "realdata.h"
#include "handeye_covariance/session/calibration_session.h"
#include "handeye_covariance/simulation/monte_carlo.h"
#include "handeye_covariance/images/image_folder.h"

namespace handeye {
namespace {

namespace fs = std::filesystem;

using test::realdata;

Eigen::Isometry3d theta_u_pose(const Eigen::Vector3d& t, const Eigen::Vector3d& theta_u) {
  return se3::make_pose(so3::exp(theta_u), t);
}

struct RealSession {
  SampleSet samples;  // each with its corners in raw pixels
  CameraModel camera;
  int images = 0, detected = 0;

  RealSession without(std::size_t k) const {
    RealSession fewer = *this;
    fewer.samples.samples.erase(fewer.samples.samples.begin() + static_cast<long>(k));
    return fewer;
  }
};

/// One of the two sessions as `handeye images` runs it (images/image_folder.h):
/// the images paired with franka_pose_rPe_<n>.yaml by their number, the camera
/// from camera_info.yaml, the pixel sigma pooled over all images first.
RealSession real_session(const fs::path& dir, Setup setup, const Target& target) {
  const std::vector<images::ImageWithPose> inputs = images::pair_images_with_poses(dir, dir);
  Rig rig{setup, {"base", "effector", "camera", "pattern"}};
  RealSession session;
  session.camera = images::read_camera((dir / "camera_info.yaml").string());
  const images::ImageSession found = images::detect_images(inputs, session.camera, target, rig);
  session.samples = found.samples;
  session.images = static_cast<int>(found.images.size());
  for (const images::ImageReport& r : found.images) {
    if (!r.used) {
      std::printf("  %s: skipped (%s)\n", r.image.c_str(), r.why.c_str());
      continue;
    }
    ++session.detected;
    std::printf("  %s: %d points, reprojection RMS %.3f px, pixel sigma %.3f px, pattern at %.3f m\n", r.image.c_str(),
                r.points, r.rms_px, r.sigma_px, r.distance);
  }
  return session;
}

/// Which of the session's doors a calibration goes through: `calibrate_checked`, as the
/// node's /calibrate, `handeye solve` and `handeye images` do (the shared robot error's
/// model where it is used, the honesty check and its inflation); or `calibrate_modelled`,
/// the same X without the honesty check (its covariance not inflated), for leave-one-out.
enum class Door { Checked, Modelled };

/// As the node: no noise config, each sample's own detection covariance; `method`
/// joint, or corners (the joint estimate refined from the corners, as the node and
/// `handeye images --method corners` run it).
Calibration calibrate_like_the_node(const SampleSet& samples, Method method = Method::Joint, Door door = Door::Checked,
                                   SharedErrorUse shared = SharedErrorUse::Use) {
  SessionConfig config;
  config.rig = samples.rig;
  SessionSettings settings = session_settings(config);
  settings.session_file.clear();
  settings.method = method;
  settings.shared_robot_error = shared;
  if (method == Method::Corners) settings.refine_corners = corner_refiner();
  CalibrationSession session(settings);
  session.replace(samples.samples, "real images");
  return door == Door::Checked ? session.calibrate_checked(session.snapshot()) : session.calibrate_modelled(session.snapshot());
}

/// Method corners (the robot poses free with the noise it estimates), with its
/// per-image reprojection RMS printed.
Calibration calibrate_by_corners(const RealSession& session) {
  const Calibration c = calibrate_like_the_node(session.samples, Method::Corners);
  for (const Calibration::CornerFit::Image& image : c.corner_fit->images) {
    std::printf("  %s: %d corners, reprojection RMS %.3f px\n", image.name.c_str(), image.corners, image.rms_px);
  }
  std::printf("  corners: %s; RMS %.3f px over %d corners\n", io::noise_model_text(c).c_str(), c.corner_fit->rms_px,
              c.corner_fit->corners);
  // A real robot's noise, estimated from the corners of 6 images or more and off its
  // floor: one target_progress holds to its rule however the pixel sigma came.
  EXPECT_TRUE(c.corner_fit->robot_noise_estimated) << io::noise_model_text(c);
  return c;
}

/// The README's "X lands within 1.6 sigma per axis of the published X" (the Franka sessions).
constexpr double kReadmeSigmas = 1.6;

using Pipeline = std::function<Calibration(const RealSession&)>;
const Pipeline by_poses = [](const RealSession& s) { return calibrate_like_the_node(s.samples); };
const Pipeline by_poses_modelled = [](const RealSession& s) {
  return calibrate_like_the_node(s.samples, Method::Joint, Door::Modelled);
};

/// X against the published X (both from the same images): within `bound` sigma per
/// axis of the combined uncertainty, ours and the jackknife spread of this pipeline's X
/// (`leave_one_out`: the same X, without the honesty check's cost) over the
/// leave-one-out sessions for theirs (8 poses determine it weakly).
Calibration judge(const RealSession& session, const Eigen::Isometry3d& published, double bound,
                  const Pipeline& calibrate = by_poses, const Pipeline& leave_one_out_calibrate = by_poses_modelled) {
  const Calibration c = calibrate(session);
  const Vector6d error = pose_error(c.T_parent_camera, published);
  std::vector<Vector6d> leave_one_out;
  for (std::size_t k = 0; k < session.samples.samples.size(); ++k) {
    leave_one_out.push_back(pose_error(leave_one_out_calibrate(session.without(k)).T_parent_camera, published));
  }
  const Vector6d ours = c.pose_covariance.diagonal().cwiseSqrt(), theirs = jackknife_sigma(leave_one_out);
  const Vector6d combined = (ours.cwiseAbs2() + theirs.cwiseAbs2()).cwiseSqrt();
  std::printf("  noise: %s\n", io::noise_model_text(c).c_str());
  for (const auto& check : c.residual_checks) {
    std::printf("  check: %s = %.3g (bound %.3g) %s\n", check.test.c_str(), check.statistic, check.bound,
                check.passed ? "passed" : "FAILED");
  }
  std::printf("  covariance: %s, loss: %s, samples used: %d, rejected: %zu\n", to_string(c.covariance_kind), to_string(c.loss),
              c.samples_used, c.rejected.size());
  const char* axes[] = {"x", "y", "z", "rx", "ry", "rz"};
  for (int a = 0; a < 6; ++a) {
    const double unit = a < 3 ? 1e3 : 180.0 / M_PI;
    std::printf("  %-2s  X - published %+8.3f %s   ours 1 sigma %.3f, published (jackknife) %.3f, combined %.3f: %+.2f sigma\n",
                axes[a], error[a] * unit, a < 3 ? "mm " : "deg", ours[a] * unit, theirs[a] * unit, combined[a] * unit,
                error[a] / combined[a]);
    EXPECT_LE(std::abs(error[a]), bound * combined[a]) << axes[a];
  }
  if (c.honesty) std::printf("  honesty: %s, inflation %.3f\n", c.honesty->text.c_str(), c.honesty->inflation);
  return c;
}

TEST(RealData, EyeToHandAprilTagThroughTheNodesPathLandsWithinTheReadmes1Point6Sigma) {
  const fs::path dir = realdata() / "visp-franka" / "data-eye-to-hand";
  ASSERT_TRUE(fs::exists(dir)) << "the real data is not at " << dir
                               << ": put shared/realdata beside the repository (or a parent of it), or set HANDEYE_REALDATA";
  std::printf("[real eye-to-hand, AprilTag, the node's path] %s\n", dir.c_str());
  // apriltag-data.txt: tag36h11 id 10, 0.048 m
  const RealSession session = real_session(dir, Setup::EyeToHand, make_target(single_tag_layout(10, 0.048)));
  EXPECT_EQ(session.detected, 8) << "every image shows the tag";
  // ViSP's published X = T_base_camera (the data's README).
  // The README's and evidence.md's figure: within 1.6 sigma per axis (a fixed session: the
  // figure is deterministic, so this bounds a regression, not a sampling spread).
  const Calibration c = judge(session,
                              theta_u_pose({0.9540358034, -0.05123574465, 0.4762201018}, {-1.104108108, -1.112745553, 1.289540899}),
                              kReadmeSigmas);
  // The detector's covariances alone are far too small for real data (robot errors,
  // calibration of the camera): the stated noise fails its chi2 test and the
  // missing part is estimated and used, not only warned about.
  ASSERT_FALSE(c.residual_checks.empty());
  EXPECT_FALSE(c.residual_checks.front().passed) << c.residual_checks.front().test;
  EXPECT_FALSE(c.noise_components.empty());
}

TEST(RealData, EyeInHandChessboardLandsWithinTheReadmes1Point6Sigma) {
  const fs::path dir = realdata() / "visp-franka" / "data-eye-in-hand";
  ASSERT_TRUE(fs::exists(dir)) << "the real data is not at " << dir;
  std::printf("[real eye-in-hand, chessboard 9 x 6 inner corners, 23.6 mm squares] %s\n", dir.c_str());
  // chessboard-data.txt, read as a target file
  const RealSession session = real_session(dir, Setup::EyeInHand,
                                           io::parse_target("{type: chessboard, inner_corners: [9, 6], square: 0.0236}",
                                                            "chessboard.yaml"));
  EXPECT_EQ(session.detected, 8) << "every image shows the board";
  // ViSP's published X = T_effector_camera (the data's README).
  judge(session, theta_u_pose({0.05771519632, -0.03392488515, -0.04227690244}, {0.001783530191, 0.009173747947, 1.581782359}),
        kReadmeSigmas);
}

// --method corners on the same real sessions: X within 3 sigma of the published X.
TEST(RealData, CornersOnTheEyeToHandAprilTagSessionLandWithin3SigmaOfThePublishedX) {
  const fs::path dir = realdata() / "visp-franka" / "data-eye-to-hand";
  ASSERT_TRUE(fs::exists(dir)) << "the real data is not at " << dir;
  std::printf("[real eye-to-hand, AprilTag, --method corners] %s\n", dir.c_str());
  const RealSession session = real_session(dir, Setup::EyeToHand, make_target(single_tag_layout(10, 0.048)));
  const Calibration c = judge(session,
                              theta_u_pose({0.9540358034, -0.05123574465, 0.4762201018}, {-1.104108108, -1.112745553, 1.289540899}),
                              3.0, calibrate_by_corners, calibrate_by_corners);
  EXPECT_EQ(c.method, Method::Corners);
}

TEST(RealData, CornersOnTheEyeInHandChessboardSessionLandWithin3SigmaOfThePublishedX) {
  const fs::path dir = realdata() / "visp-franka" / "data-eye-in-hand";
  ASSERT_TRUE(fs::exists(dir)) << "the real data is not at " << dir;
  std::printf("[real eye-in-hand, chessboard, --method corners] %s\n", dir.c_str());
  const RealSession session = real_session(dir, Setup::EyeInHand,
                                           io::parse_target("{type: chessboard, inner_corners: [9, 6], square: 0.0236}",
                                                            "chessboard.yaml"));
  const Calibration c = judge(session,
                              theta_u_pose({0.05771519632, -0.03392488515, -0.04227690244},
                                           {0.001783530191, 0.009173747947, 1.581782359}),
                              3.0, calibrate_by_corners, calibrate_by_corners);
  EXPECT_EQ(c.method, Method::Corners);
}

// `handeye images --method corners` as a user runs it on the real eye-in-hand folder:
// every image's reprojection RMS under the corner fit printed and written, the
// result's method and pattern, and --refine-intrinsics near the factory intrinsics.
TEST(RealData, HandeyeImagesWithCornersOnTheRealChessboardFolder) {
  const fs::path dir = realdata() / "visp-franka" / "data-eye-in-hand";
  ASSERT_TRUE(fs::exists(dir)) << "the real data is not at " << dir;
  const std::string tmp = test::scratch_directory();
  const std::string target = tmp + "/real_chessboard.yaml", result = tmp + "/real_corners_result.yaml";
  {
    std::ofstream(target) << "{type: chessboard, inner_corners: [9, 6], square: 0.0236}\n";
  }
  const std::string common = "images --images " + dir.string() + " --poses " + dir.string() + " --camera " +
                             (dir / "camera_info.yaml").string() + " --target " + target + " --setup eye_in_hand";
  const auto run = [&](const std::string& args, std::string& out) {
    const std::string out_file = tmp + "/real_cli_stdout";
    const int status = std::system((std::string(HANDEYE_CLI) + " " + args + " >" + out_file + " 2>&1").c_str());
    out = io::read_file(out_file);
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  };
  std::string out;
  ASSERT_EQ(run(common + " --method corners -o " + result, out), 0) << out;
  std::size_t fit_lines = 0;
  for (std::size_t at = out.find("(corner fit)"); at != std::string::npos; at = out.find("(corner fit)", at + 1)) ++fit_lines;
  EXPECT_EQ(fit_lines, 8u) << out;
  EXPECT_NE(out.find("8 images, 432 corners (corner estimator"), std::string::npos) << out;
  const YAML::Node written = YAML::LoadFile(result);
  EXPECT_EQ(written["method"].as<std::string>(), "corners");
  ASSERT_TRUE(written["pattern"]) << "Y with its covariance";
  ASSERT_EQ(written["corners"]["images"].size(), 8u);
  for (const YAML::Node& image : written["corners"]["images"]) {
    EXPECT_EQ(image["corners"].as<int>(), 54);
    EXPECT_GT(image["rms_px"].as<double>(), 0.05);  // real corners are not exact
    EXPECT_LT(image["rms_px"].as<double>(), 0.6) << image["image"].as<std::string>();
  }
  // The intrinsics refined from 8 images land near the camera file's factory values.
  ASSERT_EQ(run(common + " --method corners --refine-intrinsics -o " + result, out), 0) << out;
  const YAML::Node refined = YAML::LoadFile(result)["corners"]["intrinsics"];
  ASSERT_TRUE(refined) << out;
  std::printf("  refined fx %.2f +- %.2f, fy %.2f +- %.2f, cx %.2f, cy %.2f (camera file: 607.59, 607.58, 323.46, 243.26)\n",
              refined["fx"][0].as<double>(), refined["fx"][1].as<double>(), refined["fy"][0].as<double>(),
              refined["fy"][1].as<double>(), refined["cx"][0].as<double>(), refined["cy"][0].as<double>());
  EXPECT_NEAR(refined["fx"][0].as<double>(), 607.593, 0.03 * 607.593);
  EXPECT_NEAR(refined["fy"][0].as<double>(), 607.575, 0.03 * 607.575);
  // The printed board's own error, estimated from the corners, is in the summary and
  // the result; given as 0 the target is taken as exact.
  EXPECT_NE(out.find("target points         1 sigma"), std::string::npos) << out;
  const double target_mm = 1e3 * YAML::LoadFile(result)["corners"]["target_point_sigma"].as<double>();
  std::printf("  the printed board's points: 1 sigma %.4f mm estimated (intrinsics refined)\n", target_mm);
  EXPECT_GT(target_mm, 0.0);  // a printed board is not its file
  EXPECT_LT(target_mm, 0.5);  // nor a wrong target file
  ASSERT_EQ(run(common + " --method corners --target-error-mm 0 -o " + result, out), 0) << out;
  EXPECT_NE(out.find("exact (as given)"), std::string::npos) << out;
  EXPECT_EQ(run(common + " --method corners --target-error-mm 0.1mm -o " + result, out), 2);
  EXPECT_NE(out.find("--target-error-mm"), std::string::npos) << out;
  EXPECT_EQ(run(common + " --target-error-mm 0.1 -o " + result, out), 2);
  EXPECT_NE(out.find("add --method corners"), std::string::npos) << out;
  // The intrinsics need the corners: said before any image is read.
  EXPECT_EQ(run(common + " --refine-intrinsics -o " + result, out), 2);
  EXPECT_NE(out.find("--method corners"), std::string::npos) << out;
}

// The report (session/report.h) of each real session, as `handeye report` makes it
// from the node's samples. Real detectors understate their noise (residuals 19x
// and 51x what is stated), so every sample's sigmas are large; the advice
// threshold grows as the outlier gate's does and calls no more than a quarter of
// the samples out. The three views of X's sigma are printed: real data is where
// the covariance has been found 2x overconfident.
TEST(RealData, TheReportsOfTheRealSessions) {
  struct Case {
    const char* name;
    fs::path dir;
    handeye::Setup setup;
    Target target;
  };
  const Case cases[] = {
      {"eye-to-hand AprilTag", realdata() / "visp-franka" / "data-eye-to-hand", Setup::EyeToHand,
       make_target(single_tag_layout(10, 0.048))},
      {"eye-in-hand chessboard", realdata() / "visp-franka" / "data-eye-in-hand", Setup::EyeInHand,
       io::parse_target("{type: chessboard, inner_corners: [9, 6], square: 0.0236}", "chessboard.yaml")},
  };
  for (const Case& c : cases) {
    ASSERT_TRUE(fs::exists(c.dir)) << "the real data is not at " << c.dir;
    const RealSession session = real_session(c.dir, c.setup, c.target);
    CalibrationSession calibration(session_settings(session.samples));
    calibration.replace(session.samples.samples, c.name);
    const CalibrationReport r = make_report(calibration, calibration.snapshot());
    const int n = static_cast<int>(session.samples.samples.size());
    EXPECT_EQ(r.leave_one_out_solved, n) << c.name;
    EXPECT_GT(r.honesty.observed.splits, 30) << c.name << ": " << r.split_problem;
    int called_out = 0;
    for (const SampleFit& f : r.fits) called_out += f.sigmas > r.advice_sigma ? 1 : 0;
    EXPECT_LE(4 * called_out, n) << c.name;
    std::printf("[report, real %s, %d samples] threshold %.1f sigma, %d called out; split-half NEES %.2f\n%s", c.name, n,
                r.advice_sigma, called_out, r.honesty.observed.mean_nees, io::report_summary(r).c_str());
  }
}

/// Every real session in shared/realdata with its target and, where there is one, the
/// published X (the Franka sessions: ViSP's; the KUKA sessions: the data's README
/// gives X_park, OpenCV's calibrateHandEye (PARK) on the same files).
struct RealCase {
  const char* name;
  fs::path dir;
  Setup setup;
  Target target;
  Eigen::Isometry3d published;
};
std::vector<RealCase> real_cases() {
  const fs::path root = realdata();
  const fs::path kuka = root / "rwhe-kuka";
  return {
      {"franka eye-to-hand AprilTag", root / "visp-franka" / "data-eye-to-hand", Setup::EyeToHand,
       make_target(single_tag_layout(10, 0.048)),
       theta_u_pose({0.9540358034, -0.05123574465, 0.4762201018}, {-1.104108108, -1.112745553, 1.289540899})},
      {"franka eye-in-hand chessboard 9 x 6", root / "visp-franka" / "data-eye-in-hand", Setup::EyeInHand,
       io::parse_target("{type: chessboard, inner_corners: [9, 6], square: 0.0236}", "chessboard.yaml"),
       theta_u_pose({0.05771519632, -0.03392488515, -0.04227690244}, {0.001783530191, 0.009173747947, 1.581782359})},
      {"kuka_2 chessboard 24 x 17", kuka / "kuka_2", Setup::EyeInHand, io::read_target((kuka / "kuka_2" / "target.yaml").string()),
       theta_u_pose({0.01439, -0.1079, -0.08187}, {-1.20742, 1.28362, -1.18276})},
      {"kuka_3 ChArUco 12 x 9", kuka / "kuka_3", Setup::EyeInHand, io::read_target((kuka / "kuka_3" / "target.yaml").string()),
       theta_u_pose({0.25415, 0.0329, -0.10348}, {-1.21382, 1.27539, -1.17461})},
  };
}

/// A session on both paths a user has: the images with the detector's covariances
/// (handeye images), and the same images' poses without a covariance (a detector that
/// publishes a plain PoseStamped; the target's size known). Detected once per program:
/// three tests read them.
const std::vector<std::pair<std::string, SampleSet>>& both_paths(const RealCase& c) {
  static std::map<std::string, std::vector<std::pair<std::string, SampleSet>>> detected;
  if (const auto found = detected.find(c.name); found != detected.end()) return found->second;
  Rig rig{c.setup, {"base", "effector", "camera", "pattern"}};
  set_target(rig, c.target);
  const images::ImageSession found = images::detect_images(images::pair_images_with_poses(c.dir, c.dir),
                                                           images::read_camera((c.dir / "camera_info.yaml").string()),
                                                           c.target, rig);
  SampleSet poses = found.samples;  // the second path: no covariance anywhere
  poses.noise.reset();
  for (PoseSample& s : poses.samples) s.noise.reset(), s.corners.reset();
  return detected[c.name] = {{"images", found.samples}, {"poses without a covariance", poses}};
}

/// What a user gets on one path (calibrate_checked with the session's settings), once per
/// program: three tests start from it (deterministic, so the same whichever asks first).
const Calibration& checked_calibration(const RealCase& c, const std::string& path, const SampleSet& samples) {
  static std::map<std::string, Calibration> done;
  const std::string key = std::string(c.name) + " / " + path;
  if (const auto found = done.find(key); found != done.end()) return found->second;
  CalibrationSession session(session_settings(samples));
  session.replace(samples.samples, c.name);
  return done[key] = session.calibrate_checked(session.snapshot());
}

// Every real session on both paths, as a user runs them: the images with the
// detector's covariances (handeye images), and the same images' poses without a
// covariance (a detector that publishes a plain PoseStamped; the target's size
// known). The calibrated check (split_check.h, 200 splits against 100 simulated
// sessions at the session's own poses) gives each its ratio; the covariance a
// user reads is honest either way: the ratio within [0.8, 1.25], or the verdict
// overconfident and the covariance inflated by it (the model's kept beside it).
// The KUKA sessions' X within 3 sigma per axis of X_park (their own detections'
// OpenCV estimate), X's uncertainty being ours and the jackknife of ours.
TEST(RealData, EverySessionOnBothPathsIsJudgedAgainstItsOwnReference) {
  for (const RealCase& c : real_cases()) {
    ASSERT_TRUE(fs::exists(c.dir)) << "the real data is not at " << c.dir;
    for (const auto& [path, samples_on_path] : both_paths(c)) {
      const SampleSet* samples = &samples_on_path;
      const Calibration& cal = checked_calibration(c, path, *samples);
      ASSERT_TRUE(cal.honesty) << c.name;
      const Calibration::Honesty& h = *cal.honesty;
      ASSERT_TRUE(h.ran()) << c.name << ": " << h.text;
      const Vector6d error = pose_error(cal.T_parent_camera, c.published);
      const Vector6d sigma = cal.pose_covariance.diagonal().cwiseSqrt();
      std::printf("[honesty, real %s, %s, %zu samples] split-half NEES %.2f against %.2f (5-95%% %.2f to %.2f): ratio "
                  "%.3f (random halves %.3f; runs of %d: %.3f), %s; covariance x%.3f; X - published [%.2f %.2f %.2f] mm [%.3f %.3f %.3f] deg, in its sigma "
                  "[%.2f %.2f %.2f %.2f %.2f %.2f]; noise: %s\n",
                  c.name, path.c_str(), samples->samples.size(), h.split_half_nees, h.reference.mean, h.reference.low,
                  h.reference.high, h.ratio, h.random_ratio, h.runs.length, h.runs.ratio, h.text.c_str(), h.inflation, error(0) * 1e3, error(1) * 1e3, error(2) * 1e3,
                  error(3) * 180 / M_PI, error(4) * 180 / M_PI, error(5) * 180 / M_PI, error(0) / sigma(0),
                  error(1) / sigma(1), error(2) / sigma(2), error(3) / sigma(3), error(4) / sigma(4), error(5) / sigma(5),
                  io::noise_model_text(cal).c_str());
      EXPECT_TRUE(std::isfinite(h.ratio) && h.ratio > 0.0) << c.name;
      const bool within = h.ratio >= 0.8 && h.ratio <= 1.25;
      const bool inflated = h.verdict == Honesty::Overconfident && std::abs(h.inflation - h.ratio) < 1e-12 &&
                            cal.pose_covariance.isApprox(h.ratio * h.model_pose_covariance);
      EXPECT_TRUE(within || inflated || h.verdict == Honesty::Underconfident) << c.name << ", " << path << ": " << h.text;
      // Random halves, the figure: within [0.8, 1.25] on every session and path
      // (the KUKA sessions with the shared robot error's model, which they choose).
      EXPECT_GE(h.random_ratio, 0.8) << c.name << ", " << path;
      EXPECT_LE(h.random_ratio, 1.25) << c.name << ", " << path;
    }
  }
}

// The robot error shared by nearby poses (shared_robot_error.h) on every real session
// and both paths, fitted about the session's calibration (calibrate: the per-view
// noise model). The KUKA sessions (28 and 29 poses) choose it by BIC on both paths,
// and calibrate_checked uses it: X, Y and their covariances are its GLS ones (with
// `advice`, the per-view ones). Its linearised split-half check with GLS halves
// (cross-half terms, 100 bootstrap sessions at the session's poses, calibrate_checked's)
// reads random halves within [0.8, 1.25] and runs of 3 never overconfident. The 8-pose Franka
// sessions are below its 16 samples: the per-view model alone. Printed per session:
// the ratios of the model (and with HANDEYE_SHARED_COMPARE=1, of the model with the
// per-view estimator's halves and of the per-view model), the length and size of the shared error, sigma_X's
// change and X against X_park (the data's README) in each model's sigma.
TEST(RealData, TheSharedRobotErrorOnEverySessionAndPath) {
  for (const RealCase& c : real_cases()) {
    ASSERT_TRUE(fs::exists(c.dir)) << "the real data is not at " << c.dir;
    for (const auto& [path, samples] : both_paths(c)) {
      CalibrationSession session(session_settings(samples));
      session.replace(samples.samples, c.name);
      const SessionSnapshot snapshot = session.snapshot();
      const Calibration cal = session.calibrate(snapshot);
      const SampleSet decided = session.decided(snapshot.samples, cal);
      const SharedRobotErrorFit fit = fit_shared_robot_error(decided, cal);
      const bool kuka = std::string(c.name).find("kuka") != std::string::npos;
      // The session's own path (calibrate_checked) fits the same model and, where it is
      // chosen, uses it (X, Y and their covariances); with `advice` it keeps the per-view X.
      const Calibration& checked = checked_calibration(c, path, samples);
      SessionSettings advising = session.settings();
      advising.shared_robot_error = SharedErrorUse::Advice;
      advising.honesty.splits = 0;
      CalibrationSession advised_session(advising);
      advised_session.replace(samples.samples, c.name);
      const Calibration advised = advised_session.calibrate_checked(advised_session.snapshot());
      const std::string summary = io::human_summary(checked, io::context_of(decided));
      ASSERT_TRUE(checked.shared_robot_error) << c.name << ", " << path;
      const Calibration::SharedError& advice = *checked.shared_robot_error;
      if (!kuka) {  // 8 poses
        EXPECT_TRUE(fit.candidates.empty()) << c.name;
        EXPECT_FALSE(fit.chosen) << c.name;
        EXPECT_EQ(advice.not_fitted, "8 kept samples; it is fitted from 16 to 40") << c.name;
        EXPECT_NE(summary.find("shared robot error    not fitted: 8 kept samples"), std::string::npos) << summary;
        EXPECT_FALSE(advice.used);
        EXPECT_TRUE(checked.T_parent_camera.isApprox(cal.T_parent_camera, 1e-12));
        continue;
      }
      // The session's advice is this fit, about the same calibration.
      EXPECT_TRUE(advice.not_fitted.empty()) << advice.not_fitted;
      EXPECT_EQ(advice.chosen, fit.chosen);
      EXPECT_NEAR(advice.bic_gain, fit.bic_gain, 1e-9 * std::abs(fit.bic_gain));
      EXPECT_NEAR(advice.step_nees, fit.step_nees, 1e-9 * fit.step_nees);
      EXPECT_TRUE(advice.X.pose.isApprox(fit.T_parent_camera, 1e-12));
      EXPECT_TRUE(advice.X.covariance.isApprox(fit.pose_covariance, 1e-9));
      EXPECT_TRUE(advice.per_view_estimate_covariance.isApprox(fit.per_view_estimate_covariance, 1e-9));
      // Used: the calibration's X, Y and covariances are the model's (times the honesty
      // check's inflation, 1 unless overconfident), the per-view ones kept in the record.
      ASSERT_TRUE(checked.honesty);
      EXPECT_TRUE(advice.used);
      EXPECT_EQ(checked.covariance_kind, CovarianceKind::SharedRobotError);
      EXPECT_TRUE(checked.T_parent_camera.isApprox(fit.T_parent_camera, 1e-12));
      EXPECT_TRUE(checked.pose_covariance.isApprox(checked.honesty->inflation * fit.pose_covariance, 1e-9));
      EXPECT_TRUE(checked.pattern->pose.isApprox(fit.pattern.pose, 1e-12));
      EXPECT_TRUE(checked.cross_covariance.isApprox(checked.honesty->inflation * fit.cross_covariance, 1e-9));
      EXPECT_TRUE(advice.per_view_X.pose.isApprox(cal.T_parent_camera, 1e-12));
      EXPECT_TRUE(advice.per_view_X.covariance.isApprox(cal.pose_covariance, 1e-12));
      EXPECT_GT(fit.covariance_inflation, 1.0);  // Kenward-Roger: (s, a, b) were fitted
      EXPECT_LT(fit.covariance_inflation, 1.2);
      EXPECT_NE(summary.find("shared robot error    used: the likelihood prefers"), std::string::npos) << summary;
      EXPECT_NE(summary.find("covariance            a robot error shared by nearby poses"), std::string::npos) << summary;
      EXPECT_NE(summary.find("sigma_X is up to"), std::string::npos) << summary;  // the per-view sigma understated 2-9x
      const std::string file = io::format_result(checked, io::context_of(decided));
      EXPECT_NE(file.find("shared_robot_error:\n  chosen: true\n  used: true"), std::string::npos) << file;
      EXPECT_NE(file.find("per_view_covariance_under_it:"), std::string::npos);
      EXPECT_NE(file.find("per_view_X:"), std::string::npos);
      EXPECT_NE(file.find("\n  views:\n"), std::string::npos);  // what a check predicts new views under the model with
      // Advice: the per-view X and covariance, the model said beside them.
      ASSERT_TRUE(advised.shared_robot_error);
      EXPECT_FALSE(advised.shared_robot_error->used);
      EXPECT_TRUE(advised.shared_robot_error->chosen);
      EXPECT_TRUE(advised.T_parent_camera.isApprox(cal.T_parent_camera, 1e-12));
      EXPECT_TRUE(advised.pose_covariance.isApprox(cal.pose_covariance, 1e-12));
      EXPECT_EQ(io::format_result(advised, io::context_of(decided)).find("\n  views:\n"), std::string::npos);
      const std::string advised_summary = io::human_summary(advised, io::context_of(decided));
      EXPECT_NE(advised_summary.find("shared robot error    the likelihood prefers"), std::string::npos) << advised_summary;
      EXPECT_NE(advised_summary.find("advice only"), std::string::npos) << advised_summary;
      EXPECT_GE(fit.used.size(), 28u) << c.name;  // none rejected
      EXPECT_TRUE(fit.chosen) << c.name << ", " << path << ": BIC gain " << fit.bic_gain;
      // The model in use judged itself in calibrate_checked (GLS halves, 100 bootstrap
      // sessions): random halves within [0.8, 1.25] of its reference, its runs at most
      // 1.25 and neither look overconfident (the verdict is the worse look's; the per-view
      // model's runs are, on kuka_3).
      const Calibration::Honesty& own = *checked.honesty;
      EXPECT_GE(own.random_ratio, 0.8) << c.name << ", " << path;
      EXPECT_LE(own.random_ratio, 1.25) << c.name << ", " << path;
      EXPECT_LE(own.runs.ratio, 1.25) << c.name << ", " << path;
      EXPECT_NE(own.verdict, Honesty::Overconfident) << c.name << ", " << path;
      // The alternatives of how_it_works.md, judged the same way (40 bootstrap sessions):
      // the model with the per-view estimator's halves (its X with H0 C H0^T) and the
      // per-view model; HANDEYE_SHARED_COMPARE=1 prints them (20 s more).
      HonestyCheck shared, per_view;
      if (std::getenv("HANDEYE_SHARED_COMPARE")) {
        HonestyOptions options;
        options.run_length = 3, options.replicates = 40;
        shared = check_shared_robot_error(decided, cal, fit.best, options, SharedErrorEstimator::PerView);
        per_view = check_shared_robot_error(decided, cal, fit.per_view, options);
      }
      const std::string compared =
          shared.ran() ? "per-view halves " + number_text(shared.random_ratio, 3) + " / " + number_text(shared.runs_ratio, 3) +
                             "; per-view model " + number_text(per_view.random_ratio, 3) + " / " +
                             number_text(per_view.runs_ratio, 3)
                       : "HANDEYE_SHARED_COMPARE=1: the per-view halves and model";
      EXPECT_LT(fit.step_nees, 22.46) << c.name << ", " << path;  // chi2(6) 99.9%: the model explains why X moved
      const Vector6d s_true = fit.per_view_estimate_covariance.diagonal().cwiseSqrt();
      const Vector6d s0 = cal.pose_covariance.diagonal().cwiseSqrt(), s1 = fit.pose_covariance.diagonal().cwiseSqrt();
      const Vector6d e0 = pose_error(cal.T_parent_camera, c.published), e1 = pose_error(fit.T_parent_camera, c.published);
      std::printf("[shared robot error, real %s, %s, %zu samples] chosen %d (BIC gain %.1f): l %.2f m, %.2f mm, %.3f deg, "
                  "view noise x%.3f, Kenward-Roger x%.3f; split-half ratio random / runs of 3: %.2f / %.2f (%s); "
                  "sigma_X / per-view [%.2f %.2f %.2f %.2f %.2f %.2f]; X - published in sigma: per-view [%.1f %.1f %.1f "
                  "%.1f %.1f %.1f], shared [%.1f %.1f %.1f %.1f %.1f %.1f]; X's step NEES %.2f; the per-view sigma_X "
                  "under the model / its own [%.2f %.2f %.2f %.2f %.2f %.2f]\n",
                  c.name, path.c_str(), fit.used.size(), fit.chosen ? 1 : 0, fit.bic_gain, fit.best.length_scale,
                  fit.best.translation_sigma * 1e3, fit.best.rotation_sigma * 180.0 / M_PI, fit.best.view_noise_scale, fit.covariance_inflation,
                  own.random_ratio, own.runs.ratio, compared.c_str(), s1(0) / s0(0),
                  s1(1) / s0(1), s1(2) / s0(2), s1(3) / s0(3), s1(4) / s0(4), s1(5) / s0(5), e0(0) / s0(0), e0(1) / s0(1),
                  e0(2) / s0(2), e0(3) / s0(3), e0(4) / s0(4), e0(5) / s0(5), e1(0) / s1(0), e1(1) / s1(1), e1(2) / s1(2),
                  e1(3) / s1(3), e1(4) / s1(4), e1(5) / s1(5), fit.step_nees, s_true(0) / s0(0), s_true(1) / s0(1),
                  s_true(2) / s0(2), s_true(3) / s0(3), s_true(4) / s0(4), s_true(5) / s0(5));
    }
  }
}

/// Every k-subset of 0..n-1 once, each as an order whose first k are the subset's, when
/// there are no more than `most` of them; none otherwise.
std::vector<std::vector<int>> every_split(int n, int k, int most) {
  double subsets = 1.0;
  for (int i = 0; i < k; ++i) subsets = subsets * (n - i) / (i + 1);
  std::vector<std::vector<int>> orders;
  if (subsets > most) return orders;
  std::vector<bool> in_check(static_cast<std::size_t>(n), false);
  std::fill(in_check.begin(), in_check.begin() + k, true);
  do {
    std::vector<int> order;
    for (int pass = 0; pass < 2; ++pass) {
      for (int i = 0; i < n; ++i) {
        if (in_check[static_cast<std::size_t>(i)] == (pass == 0)) order.push_back(i);
      }
    }
    orders.push_back(order);
  } while (std::prev_permutation(in_check.begin(), in_check.end()));
  return orders;
}

/// What the checks of one session's splits found.
struct SplitChecks {
  int splits = 0, alarms = 0, allowed = 0, detected_allowed = 0, detected = 0, per_view_parts = 0;
  std::vector<double> detectable;  // 5 sigma along each move, m
};

/// A part of a session calibrated as a user's would be (ChecksOfACalibrationOnEverySession):
/// its noise model and leave-one-out prediction, the whole session's honesty `inflation`
/// and shared robot error model (`own_model`: the part fits its own; `per_view` says when
/// the part's own fit kept the per-view model). nullopt for a part the estimator refuses.
std::optional<Calibration> part_calibration(const SampleSet& part, const char* name, double inflation,
                                            const std::optional<SharedRobotError>& shared, bool own_model, bool* per_view) {
  SessionSettings settings = session_settings(part);
  settings.honesty.splits = 0;  // the whole session's inflation stands in for it
  // Where the whole session uses the shared robot error, a part takes its model
  // (length, s, a, b) as it takes its inflation, fitted with the check's views among
  // the session's: fitting each part's own would cost 200 x 0.1 s per session and
  // path. HANDEYE_CHECK_OWN_MODEL=1 fits each part's own, as a user's would be (the
  // figures of both in docs/how_it_works.md).
  settings.shared_robot_error = SharedErrorUse::Off;
  CalibrationSession session(settings);
  session.replace(part.samples, name);
  Calibration cal;
  try {
    // With its leave-one-out prediction; under the shared robot error the session
    // makes none (the check predicts under the model), as here.
    cal = shared ? session.calibrate(session.snapshot()) : session.calibrate_checked(session.snapshot());
  } catch (const HandEyeError&) {
    return std::nullopt;
  }
  if (shared) {
    SharedRobotErrorOptions options;
    if (!own_model) options.model = shared;
    const SharedRobotErrorFit fit = fit_shared_robot_error(session.decided(part, cal), cal, options);
    if (fit.chosen) {
      cal.shared_robot_error = shared_error_record(fit);
      use_shared_robot_error(cal, fit);
    } else {  // the part's own fit keeps the per-view model: its leave-one-out too
      cal = session.calibrate_checked(session.snapshot());
      *per_view = true;
    }
  }
  if (inflation > 1.0) {
    scale_covariances(cal, inflation);
    cal.honesty = Calibration::Honesty{};
    cal.honesty->inflation = inflation;
  }
  return cal;
}

/// The checks of `samples`' splits into a calibration and `k` check views (each of
/// `distinct` once, else 200 random ones drawn from `rng`), each calibrated as a user's
/// would be (ChecksOfACalibrationOnEverySession); with `moves`, each split's check views
/// are checked again with the camera moved 2 mm on its mount (drawn from `rng`).
/// `own_model`: a part fits its own shared robot error instead of taking `shared`.
SplitChecks check_splits(const SampleSet& samples, const char* name, int k, const std::vector<std::vector<int>>& distinct,
                         double inflation, const std::optional<SharedRobotError>& shared, bool own_model, bool moves,
                         std::mt19937_64& rng) {
  const int n = static_cast<int>(samples.samples.size());
  const int planned = distinct.empty() ? 200 : static_cast<int>(distinct.size());
  std::normal_distribution<double> normal(0.0, 1.0);
  SplitChecks found;
  for (int split = 0; split < planned; ++split) {
    std::vector<int> order(static_cast<std::size_t>(n));
    std::iota(order.begin(), order.end(), 0);
    if (distinct.empty()) {
      std::shuffle(order.begin(), order.end(), rng);
    } else {
      order = distinct[static_cast<std::size_t>(split)];
    }
    SampleSet part = samples, views = samples;
    part.samples.clear(), views.samples.clear();
    for (int i = 0; i < n; ++i) {
      (i < k ? views : part).samples.push_back(samples.samples[static_cast<std::size_t>(order[static_cast<std::size_t>(i)])]);
    }
    bool per_view = false;
    const std::optional<Calibration> calibrated = part_calibration(part, name, inflation, shared, own_model, &per_view);
    if (!calibrated) continue;  // a part the estimator refuses (too few turns) is no calibration to check
    const Calibration& cal = *calibrated;
    found.per_view_parts += per_view;
    ++found.splits;
    const CalibrationCheck unchanged = check_calibration(cal, views);
    found.alarms += unchanged.changed;
    if (!moves) continue;
    // The camera moved by 2 mm on its mount: X' = X T(delta), so each detected pose
    // T_camera_pattern becomes T(-delta) T_camera_pattern.
    Eigen::Vector3d delta(normal(rng), normal(rng), normal(rng));
    delta = 2e-3 * delta.normalized();
    SampleSet moved = views;
    for (PoseSample& s : moved.samples) s.T_camera_pattern.translation() -= delta;
    const CalibrationCheck check = check_calibration(cal, moved);
    Vector6d u = Vector6d::Zero();
    u.head<3>() = cal.T_parent_camera.linear() * delta.normalized();  // the move as X's left perturbation
    const double sigma = 1.0 / std::sqrt(u.dot(unchanged.X_alone.X_change->covariance.ldlt().solve(u)));
    found.detectable.push_back(5.0 * sigma);
    found.detected += check.changed;
    if (5.0 * sigma <= 2e-3) ++found.allowed, found.detected_allowed += check.changed;
  }
  return found;
}

/// A count of alarms against `replicates` counts drawn by `draw` (sessions simulated and
/// their splits checked alike): their mean and 5-95% spread, and the count as a
/// Monte-Carlo p-value (Besag and Clifford).
struct AlarmReference {
  double mean = 0.0, low = 0.0, high = 0.0, p_value = 1.0;
  int percent_as_many = 0, percentile_95 = 0;
  std::vector<int> counts;  // sorted
};
AlarmReference alarm_reference(int alarms, int replicates, const std::function<int()>& draw) {
  if (replicates < 20) throw std::invalid_argument("a reference of fewer than 20 sessions has no 95th percentile");
  AlarmReference r;
  for (int b = 0; b < replicates; ++b) r.counts.push_back(draw());
  std::sort(r.counts.begin(), r.counts.end());
  const int as_many = static_cast<int>(std::count_if(r.counts.begin(), r.counts.end(), [&](int a) { return a >= alarms; }));
  r.mean = std::accumulate(r.counts.begin(), r.counts.end(), 0.0) / replicates;
  r.p_value = (as_many + 1.0) / (replicates + 1.0);
  r.percent_as_many = 100 * as_many / replicates;
  const std::vector<double> spread(r.counts.begin(), r.counts.end());
  r.low = linear_quantile(spread, 0.05), r.high = linear_quantile(spread, 0.95);
  r.percentile_95 = r.counts[static_cast<std::size_t>(95 * replicates / 100 - 1)];
  return r;
}

/// The eye-in-hand Franka session's images are not of one calibration: views 7 and 8 (the
/// last two) checked against a calibration of views 1-6 are changed beyond doubt, named X
/// with odds beyond 19 : 1, and one change explains both (what it leaves is within the
/// noise); none of views 1-6 is out against the other five (a weak test: one view against
/// a 5-view calibration). The part without the change, views 1-6 alone, split as the
/// session is (4 + 2), raises no more alarms than its own reference. With
/// HANDEYE_MOVED_REFERENCE=1, its `alarms` over the `distinct`
/// splits are also judged against sessions simulated at its robot poses with the model of
/// views 1-6 (X, Y, their noise), views 7 and 8 seeing X moved by that change (100
/// sessions, 14 s).
void views_7_and_8_moved(const SampleSet& samples, const char* name, int k,
                         const std::vector<std::vector<int>>& distinct, int alarms) {
  const std::size_t first = 6;
  ASSERT_EQ(samples.samples.size(), 8u) << name << ": every image detected, in the folder's order";
  for (std::size_t i = 0; i < samples.samples.size(); ++i) {
    const std::shared_ptr<const TargetCorners>& corners = samples.samples[i].corners;
    ASSERT_TRUE(corners) << name << ", sample " << i;
    EXPECT_NE(corners->source.find("image-" + std::to_string(i + 1) + "."), std::string::npos) << corners->source;
  }
  SampleSet before = samples, after = samples;
  before.samples.resize(first);
  after.samples.erase(after.samples.begin(), after.samples.begin() + static_cast<std::ptrdiff_t>(first));
  bool per_view = false;
  const std::optional<Calibration> calibrated = part_calibration(before, name, 1.0, std::nullopt, false, &per_view);
  ASSERT_TRUE(calibrated) << "views 1-6 of " << name << " do not calibrate";
  const Calibration& cal = *calibrated;
  std::printf("  views 1-6's noise: %s\n", io::noise_model_text(cal).c_str());
  const CalibrationCheck moved = check_calibration(cal, after);
  ASSERT_EQ(moved.change.what, ChangedPose::X) << name;
  const EstimatedChange::Delta& d = *moved.change.X_change;
  // Each part of the change against its own covariance: chi2 on 3 dof.
  const auto part_chi2 = [&](int at) {
    const Eigen::Vector3d v = d.value.segment<3>(at);
    return v.dot(d.covariance.block<3, 3>(at, at).ldlt().solve(v));
  };
  std::printf("  views 7 and 8 against a calibration of views 1-6: %s (p = %.2g), X moved (odds over Y %.3g : 1) by "
              "%.2f mm (chi2 %.1f on 3 dof) and %.3f deg (chi2 %.1f on 3 dof); left after it chi2 %.1f on %d dof "
              "(p = %.2f)\n",
              moved.changed ? "changed" : "consistent", moved.p_value, moved.naming_odds, d.value.head<3>().norm() * 1e3,
              part_chi2(0), d.value.tail<3>().norm() * 180.0 / M_PI, part_chi2(3), moved.change.residual_chi2,
              moved.dof - moved.change.dof, moved.change.residual_p_value);
  EXPECT_TRUE(moved.changed) << name;
  EXPECT_LT(moved.p_value, 1e-4) << name;
  EXPECT_GE(moved.naming_odds, 19.0) << name;
  EXPECT_GT(moved.change.residual_p_value, 0.01) << name << ": one change explains views 7 and 8";
  // The same without the noise model: each view's rotation residual (camera frame) about a
  // calibration without it, views 1-6 each about the other five, 7 and 8 about 1-6.
  const auto rotation_residual = [&](const Calibration& c, const PoseSample& view) -> Eigen::Vector3d {
    return joint_residual(samples.rig, view, c.T_parent_camera, c.pattern->pose).error.tail<3>();
  };
  std::vector<Eigen::Vector3d> after_residuals;  // views 7's and 8's
  double predicted_degrees = 0.0;  // the largest predicted 1 sigma per axis of 7's and 8's, calibration's error included
  for (const PoseSample& view : after.samples) {
    const SampleSet one{samples.rig, samples.noise, {view}};
    const JointResidual r = joint_residual(samples.rig, view, cal.T_parent_camera, cal.pattern->pose);
    after_residuals.push_back(r.error.tail<3>());
    const Matrix6d C = residual_covariances(one, cal)[0] + r.jacobian * joint_covariance(cal) * r.jacobian.transpose();
    predicted_degrees = std::max(predicted_degrees, C.diagonal().tail<3>().cwiseSqrt().maxCoeff() * 180.0 / M_PI);
  }
  const Eigen::Vector3d& r7 = after_residuals[0];
  const Eigen::Vector3d& r8 = after_residuals[1];
  std::vector<double> before_degrees;
  std::printf("  each of views 1-6 against the other five: p =");
  for (std::size_t left = 0; left < first; ++left) {
    SampleSet others = before, one = before;
    others.samples.erase(others.samples.begin() + static_cast<std::ptrdiff_t>(left));
    one.samples = {before.samples[left]};
    const std::optional<Calibration> rest = part_calibration(others, name, 1.0, std::nullopt, false, &per_view);
    if (!rest) {
      ADD_FAILURE() << name << ", views 1-6 without " << left + 1 << " do not calibrate";
      continue;
    }
    const CalibrationCheck one_check = check_calibration(*rest, one);
    std::printf(" %.2g", one_check.p_value);
    EXPECT_FALSE(one_check.changed) << name << ": view " << left + 1 << " against the other five";
    before_degrees.push_back(rotation_residual(*rest, before.samples[left]).norm() * 180.0 / M_PI);
  }
  std::printf("\n");
  const double apart = std::acos(std::clamp(r7.normalized().dot(r8.normalized()), -1.0, 1.0)) * 180.0 / M_PI;
  std::printf("  rotation residuals, each of views 1-6 about the other five:");
  for (double d : before_degrees) std::printf(" %.2f", d);
  std::printf(" deg; views 7 and 8 about 1-6: %.2f and %.2f deg, %.0f deg apart (predicted 1 sigma per axis at most "
              "%.2f deg)\n",
              r7.norm() * 180.0 / M_PI, r8.norm() * 180.0 / M_PI, apart, predicted_degrees);
  // Views 7 and 8 are off more than any of the six and the same way: under no change the
  // two largest of 8 exchangeable residuals are those two in 1 of 28, and two independent
  // directions within 30 degrees in about 7% (1 - cos 30 over 2), or 17% in a plane.
  const double largest_before = *std::max_element(before_degrees.begin(), before_degrees.end());
  EXPECT_GT(std::min(r7.norm(), r8.norm()) * 180.0 / M_PI, largest_before) << name;
  EXPECT_LT(apart, 30.0) << name;
  // The false alarms of the part of the session without a change: the splits of views 1-6
  // alone, 4 to calibrate and 2 to check as the session's own, against sessions simulated
  // at their poses with views 1-6's model (printed above), the same splits checked alike
  // (about 5 s). The splits draw nothing (each once, no move).
  {
    const std::vector<std::vector<int>> own = every_split(static_cast<int>(first), k, 200);
    std::mt19937_64 unused(0);
    const SplitChecks found = check_splits(before, name, k, own, 1.0, std::nullopt, false, false, unused);
    const std::vector<Matrix6d> S = residual_covariances(before, cal);
    std::mt19937_64 rng(37);
    const AlarmReference reference = alarm_reference(found.alarms, 100, [&] {
      const SampleSet replicate = simulate_like(before, cal, S, rng);
      std::mt19937_64 unused_here(0);
      return check_splits(replicate, name, k, own, 1.0, std::nullopt, false, false, unused_here).alarms;
    });
    std::printf("[check, real %s, views 1-6 alone, 2 per check] %d of %zu splits calibrated: false alarms %d; reference "
                "(100 sessions at their poses and views 1-6's noise): mean %.2f alarms, 5-95%% %.1f to %.1f; %d or more "
                "in %d%% of them (p = %.3f)\n",
                name, found.splits, own.size(), found.alarms, reference.mean, reference.low, reference.high, found.alarms,
                reference.percent_as_many, reference.p_value);
    EXPECT_EQ(found.splits, static_cast<int>(own.size())) << name << ": every 4-view part of views 1-6 calibrates";
    EXPECT_LE(reference.mean / static_cast<double>(own.size()), 0.03) << name;
    EXPECT_GT(reference.p_value, 0.01) << name << ": views 1-6 alone";
  }
  if (!std::getenv("HANDEYE_MOVED_REFERENCE")) return;
  // The reference: every view simulated with views 1-6's model (simulate_like), views 7 and
  // 8 with the same model and X moved by the change.
  const std::vector<Matrix6d> S = residual_covariances(samples, cal);
  Calibration moved_cal = cal;
  moved_cal.T_parent_camera = test::apply(cal.T_parent_camera, d.value);
  std::mt19937_64 rng(31);
  const AlarmReference reference = alarm_reference(alarms, 100, [&] {
    SampleSet replicate = simulate_like(samples, cal, S, rng);
    const SampleSet after_the_move = simulate_like(samples, moved_cal, S, rng);
    std::copy(after_the_move.samples.begin() + static_cast<std::ptrdiff_t>(first), after_the_move.samples.end(),
              replicate.samples.begin() + static_cast<std::ptrdiff_t>(first));
    std::mt19937_64 unused(0);
    return check_splits(replicate, name, k, distinct, 1.0, std::nullopt, false, false, unused).alarms;
  });
  std::printf("  reference with views 7 and 8 moved so (100 sessions at its poses and views 1-6's noise, the same %zu "
              "splits): mean %.2f alarms, 5-95%% %.1f to %.1f; %d or more in %d%% of them (p = %.3f)\n",
              distinct.size(), reference.mean, reference.low, reference.high, alarms, reference.percent_as_many,
              reference.p_value);
}

// The check of a saved calibration (calibration_check.h) on every real session and both paths: 200
// random splits (each distinct split once where there are fewer) into a calibration part and a
// check part of 5 views (a third of a short session), the calibration as a user gets it (the
// session's noise model and its leave-one-out prediction scale, its covariance inflated by the
// honesty check's factor of the whole session: the splits' own would cost 200 honesty checks;
// where the whole session uses the shared robot error, the part uses its model too, and the check
// predicts the new views under it). A view beyond the outlier gate alone is left out as a wrong
// detection, as the check does. Without a change the check says "changed" in at most 3% of the
// splits at alpha 1% (a short session's few splits: their count of alarms against a parametric-
// bootstrap reference at its size and noise); with the camera moved 2 mm on its mount (the check
// part's detected poses shifted by 2 mm in the camera frame, a random direction per split) it
// detects it in at least 90% of the splits whose calibration's sigma allows it: where 2 mm is at
// least the check's own 5 sigma along the move, the change the bound lets any such test detect
// about 90% of the time. The detectable change (5 sigma, median over the splits) is printed per
// session.
TEST(RealData, ChecksOfACalibrationOnEverySession) {
  for (const RealCase& c : real_cases()) {
    ASSERT_TRUE(fs::exists(c.dir)) << "the real data is not at " << c.dir;
    for (const auto& [path, samples_on_path] : both_paths(c)) {
      const SampleSet* samples = &samples_on_path;
      double inflation = 1.0;
      std::optional<SharedRobotError> shared;  // the whole session's, where it uses one
      Calibration whole_calibration;
      {
        whole_calibration = checked_calibration(c, path, *samples);
        if (whole_calibration.honesty) inflation = whole_calibration.honesty->inflation;
        if (whole_calibration.shared_robot_error && whole_calibration.shared_robot_error->used) {
          shared = model_of(*whole_calibration.shared_robot_error);
        }
      }
      const int n = static_cast<int>(samples->samples.size());
      const int k = std::min(5, n / 3);
      std::mt19937_64 rng(17);
      // 200 random splits; or, where a session has fewer distinct ones (8 views, checks
      // of 2: 28), each of them once: repeating a split would only weight it again.
      const std::vector<std::vector<int>> distinct = every_split(n, k, 200);
      const int planned = distinct.empty() ? 200 : static_cast<int>(distinct.size());
      const bool own_model = std::getenv("HANDEYE_CHECK_OWN_MODEL") != nullptr;
      SplitChecks found = check_splits(*samples, c.name, k, distinct, inflation, shared, own_model, true, rng);
      std::vector<double>& detectable = found.detectable;
      std::sort(detectable.begin(), detectable.end());
      const double median = detectable.empty() ? 0.0 : detectable[detectable.size() / 2];
      const int splits = found.splits, alarms = found.alarms;
      const double alarm_rate = splits ? static_cast<double>(alarms) / splits : 1.0;
      // The one session whose views are not of one calibration (views_7_and_8_moved).
      const bool holds_a_change = std::string(c.name) == "franka eye-in-hand chessboard 9 x 6" && path == "images";
      if (own_model && shared) {
        std::printf("  (each part's own shared robot error: per-view model in %d parts)\n", found.per_view_parts);
      }
      std::printf("[check, real %s, %s, %d samples, %d per check, covariance x%.2f] %d splits: false alarms %.1f%% (%d); "
                  "camera moved 2 mm: detected %.1f%% (%d of %d splits whose 5 sigma <= 2 mm: %.1f%%); detectable change "
                  "(5 sigma along the move, median) %.2f mm\n",
                  c.name, path.c_str(), n, k, inflation, splits, 100.0 * alarm_rate, alarms,
                  splits ? 100.0 * found.detected / splits : 0.0, found.detected_allowed, found.allowed,
                  found.allowed ? 100.0 * found.detected_allowed / found.allowed : 0.0, median * 1e3);
      EXPECT_GE(splits, std::min(150, planned)) << c.name << ", " << path;
      if (distinct.empty()) {
        // The KUKA sessions, whose calibration uses the shared robot error, predicted under it.
        EXPECT_LE(alarm_rate, 0.03) << c.name << ", " << path;
      } else if (alarms > 0) {  // (no alarm is within any reference)
        // A short session's few splits share their views: one odd view is in a quarter of
        // them, so the count of alarms over its splits is judged against a reference at the
        // session's own size and noise: the same splits of sessions simulated at its robot
        // poses with its fitted noise (split_check.h's simulate_like), checked alike.
        // The replicates take the session's inflation and model as the splits do: right
        // where there is neither (a short session: no shared robot error below 16 views).
        EXPECT_TRUE(inflation == 1.0 && !shared) << c.name << ", " << path << ": the reference assumes its model as fitted";
        const std::vector<Matrix6d> S = residual_covariances(*samples, whole_calibration);
        std::mt19937_64 replicate_rng(29);
        const AlarmReference reference = alarm_reference(alarms, 100, [&] {
          const SampleSet replicate = simulate_like(*samples, whole_calibration, S, replicate_rng);
          return check_splits(replicate, c.name, k, distinct, inflation, shared, false, false, replicate_rng).alarms;
        });
        const double p_value = reference.p_value;
        std::printf("  reference (100 sessions at its poses and noise, the same %d splits): mean %.2f alarms (%.1f%%), "
                    "95th percentile %d, max %d; %d or more in %d%% of them (p = %.3f)\n",
                    planned, reference.mean, 100.0 * reference.mean / planned, reference.percentile_95,
                    reference.counts.back(), alarms, reference.percent_as_many, p_value);
        // The reference itself keeps alpha: its mean within 3% ...
        EXPECT_LE(reference.mean / planned, 0.03) << c.name << ", " << path;
        // ... and the session's own count is within it (p above 1%). Not on the eye-in-hand
        // Franka session's images, which hold a change: its views 7 and 8 are not of one
        // calibration with views 1-6 (views_7_and_8_moved), and its 4 alarms each check view
        // 8 against a calibration of mostly unchanged views, where "no change" does not hold.
        // Its false alarms are judged on its unchanged part, views 1-6 alone (within their
        // reference). A reference that holds the change as a step of X does not raise 4
        // (HANDEYE_MOVED_REFERENCE=1: mean 1.00, 0 of 100): the change is more than that
        // step, or the check sharper there than that reference; the data cannot say which.
        // There the count is held where it is, below 20%.
        if (holds_a_change) {
          EXPECT_LE(alarm_rate, 0.2) << c.name << ", " << path;
        } else {
          EXPECT_GT(p_value, 0.01) << c.name << ", " << path;
        }
      }
      if (holds_a_change) views_7_and_8_moved(*samples, c.name, k, distinct, alarms);
      if (found.allowed >= 20) {
        EXPECT_GE(static_cast<double>(found.detected_allowed) / found.allowed, 0.9) << c.name << ", " << path;
      }
    }
  }
}

// The KUKA sessions through the node's door (calibrate_checked), as evidence.md states them:
// the per-view model's X (the shared robot error off) within 3 sigma of X_park per axis
// (combined with the jackknife spread of that pipeline for X_park's, as the Franka sessions
// are judged against ViSP's); and the X users get, the shared robot error's, used, its step
// from the per-view X explained by its own covariance (NEES below chi2(6)'s 99%, 16.81). X_park
// is OpenCV's PARK on the same detections, not a truth: the model's X is printed against it.
TEST(RealData, KukaSessionsThroughTheNodesDoorAsEvidenceStatesThem) {
  const Pipeline per_view = [](const RealSession& s) {
    return calibrate_like_the_node(s.samples, Method::Joint, Door::Checked, SharedErrorUse::Off);
  };
  const Pipeline per_view_modelled = [](const RealSession& s) {
    return calibrate_like_the_node(s.samples, Method::Joint, Door::Modelled, SharedErrorUse::Off);
  };
  for (const RealCase& c : real_cases()) {
    if (std::string(c.name).rfind("kuka", 0) != 0) continue;
    ASSERT_TRUE(fs::exists(c.dir)) << "the real data is not at " << c.dir;
    std::printf("[real %s, the node's door, the per-view model] %s\n", c.name, c.dir.c_str());
    const RealSession session = real_session(c.dir, c.setup, c.target);
    EXPECT_EQ(session.detected, session.images) << "every image shows the board";
    judge(session, c.published, 3.0, per_view, per_view_modelled);
    const Calibration used = by_poses(session);
    ASSERT_TRUE(used.shared_robot_error.has_value()) << c.name;
    const Calibration::SharedError& e = *used.shared_robot_error;
    EXPECT_TRUE(e.used) << c.name << ": " << e.not_fitted;
    const Vector6d error = pose_error(used.T_parent_camera, c.published);
    const Vector6d sigma = used.pose_covariance.diagonal().cwiseSqrt();
    std::printf("[real %s, the node's door, the shared robot error] step NEES %.2f (chi2(6) 99%%: 16.81), honesty %s\n",
                c.name, e.step_nees, used.honesty ? used.honesty->text.c_str() : "not run");
    std::printf("  the model's X - X_park in its own sigma (measured, not asserted):");
    for (int a = 0; a < 6; ++a) std::printf(" %+.2f", error[a] / sigma[a]);
    std::printf("\n");
    EXPECT_LE(e.step_nees, 16.81) << c.name;
    // evidence.md's figures for the images path (deterministic: a regression guard, to the digits quoted).
    const double quoted = std::string(c.name).rfind("kuka_2", 0) == 0 ? 8.83 : 3.77;
    EXPECT_NEAR(e.step_nees, quoted, 0.005) << c.name;
  }
}

}  // namespace
}  // namespace handeye
