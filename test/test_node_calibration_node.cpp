// Client of calibration_node.test: the rig moves through 12 poses; the node
// auto-samples; /calibrate must return the rig's X with an honest covariance.
#include <geometry_msgs/PoseStamped.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include <visualization_msgs/MarkerArray.h>
#include <yaml-cpp/yaml.h>

#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/fisher_f.hpp>

#include <cstdio>
#include <filesystem>

#include "handeye_covariance/simulation/monte_carlo.h"
#include "handeye_covariance/io/yaml_io.h"
#include "handeye_covariance/ros/msg_conversion.h"
#include "node_test_helpers.h"

namespace handeye {
namespace {

// Set per launch file (private params of this test node).
std::string kNs, kParent, kNoiseOrigin, kMethod;

TEST(CalibrationNode, AutoSamplesTheRigAndCalibratesWithAnHonestCovariance) {
  ros::NodeHandle nh;
  test::TruthWatcher rig;
  geometry_msgs::PoseWithCovarianceStamped published;
  bool have_published = false;
  auto calibration_sub = nh.subscribe<geometry_msgs::PoseWithCovarianceStamped>(
      kNs + "handeye_calibration/calibration", 1, [&](const auto& msg) {
        published = *msg;
        have_published = true;
      });
  test::StatusWatcher status(kNs + "handeye_calibration/status");
  std::size_t markers = 0;
  geometry_msgs::PoseWithCovarianceStamped running;
  auto markers_sub = nh.subscribe<visualization_msgs::MarkerArray>(
      kNs + "handeye_calibration/markers", 1, [&](const auto& msg) { markers = msg->markers.size(); });
  auto estimate_sub = nh.subscribe<geometry_msgs::PoseWithCovarianceStamped>(
      kNs + "handeye_calibration/estimate", 1, [&](const auto& msg) { running = *msg; });
  ASSERT_TRUE(test::wait_for([&] { return rig.received; }, 20.0)) << "no truth from the rig";

  // 12 poses, 1.7 s each: the node must take a sample at (nearly) every pause.
  ASSERT_TRUE(test::wait_for([&] { return status.received && status.latest.samples >= 10; }, 60.0))
      << "samples: " << status.latest.samples << ", last event: " << status.latest.last_event;
  // Then until the rig has stopped at its last pose (no new sample for 3.5 s, more
  // than a pause and a move): the save/load round trip below compares with this X.
  for (int last = -1; last != static_cast<int>(status.latest.samples);) {
    last = static_cast<int>(status.latest.samples);
    test::wait_for([&] { return static_cast<int>(status.latest.samples) != last; }, 3.5);
  }
  // The worker follows each new sample with its estimate (within one solve and ranking).
  EXPECT_TRUE(test::wait_for(
      [&] { return status.latest.has_estimate && status.latest.estimate_samples == status.latest.samples; }, 10.0))
      << status.latest.estimate_samples << " of " << status.latest.samples << " samples; " << status.latest.last_event;
  EXPECT_GT(status.latest.object_error_mm, 0.0);
  EXPECT_EQ(status.latest.parent_frame, kParent);
  // The running estimate and its markers (position ellipsoid, 3 discs, label) for RViz.
  EXPECT_TRUE(test::wait_for([&] { return markers == 5 && running.header.frame_id == kParent; }, 5.0))
      << markers << " markers, estimate in `" << running.header.frame_id << "`";

  Calibrate calibrate;
  ASSERT_TRUE(test::call(kNs + "calibrate", calibrate));
  ASSERT_TRUE(calibrate.response.success) << calibrate.response.message;
  EXPECT_EQ(calibrate.response.calibration.header.frame_id, kParent);
  EXPECT_GE(calibrate.response.samples_used, 10);
  EXPECT_EQ(calibrate.response.noise_origin, kNoiseOrigin);
  // Every key of the result file comes back in `result`, in the file's order and as it has it.
  const auto entry = [&](const std::string& key) {
    for (const auto& kv : calibrate.response.result) {
      if (kv.key == key) return kv.value;
    }
    return std::string("<absent>");
  };
  ASSERT_FALSE(calibrate.response.result.empty());
  const YAML::Node written = YAML::LoadFile(calibrate.response.calibration_file);
  EXPECT_EQ(calibrate.response.result.front().key, written.begin()->first.as<std::string>());
  EXPECT_EQ(entry("samples_used"), std::to_string(calibrate.response.samples_used));
  EXPECT_EQ(entry("method"), calibrate.response.method);
  EXPECT_EQ(entry("noise.origin"), kNoiseOrigin);
  EXPECT_EQ(entry("honesty.verdict"), calibrate.response.honesty.empty() ? "<absent>" : calibrate.response.honesty);
  EXPECT_EQ(entry("solver.rotation.iterations"), std::to_string(calibrate.response.rotation_iterations));

  // Within the predicted uncertainty of the truth: the 6-dof NEES below its
  // 99.9% quantile, chi2(6) when the noise is given. When it is estimated from
  // the residuals its scale is itself uncertain: the joint estimator's noise
  // variances rest on n - 2 samples' worth of residuals, and the NEES follows
  // about 6 F(6, n - 2).
  const PoseWithCovariance X = conversions::to_core(calibrate.response.calibration.pose);
  const Vector6d error = pose_error(X.pose, conversions::to_eigen(rig.truth.pose));
  const double nees = error.dot(X.covariance.ldlt().solve(error));
  const int used = calibrate.response.samples_used;
  const double bound = kNoiseOrigin == "given"
                           ? boost::math::quantile(boost::math::chi_squared(6.0), 0.999)
                           : 6.0 * boost::math::quantile(boost::math::fisher_f(6.0, used - 2.0), 0.999);
  std::printf("X from %d samples: NEES %.2f (99.9%% bound %.1f), error %.3f mm / %.4f deg, worst-axis sigma %.3f mm\n", used,
              nees, bound, error.head<3>().norm() * 1e3, error.tail<3>().norm() * 180.0 / M_PI,
              max_sigma(X.covariance.topLeftCorner<3, 3>().eval()) * 1e3);
  EXPECT_LT(nees, bound) << "error " << error.transpose();
  EXPECT_LT(error.head<3>().norm(), 0.003);
  // The joint estimator gives the pattern's pose Y too, in its parent frame, just as honest.
  EXPECT_EQ(calibrate.response.method, kMethod);
  if (kMethod == "corners") {
    // Every sample holds its detection's corners: the fit, the file and the session file say so.
    std::printf("corners: %d corners, pixel sigma %.3f px, reprojection RMS %.3f px\n", calibrate.response.corners_used,
                calibrate.response.corner_pixel_sigma, calibrate.response.corner_rms_px);
    EXPECT_GE(calibrate.response.corners_used, 4 * used);
    EXPECT_GT(calibrate.response.corner_pixel_sigma, 0.0);
    EXPECT_GT(calibrate.response.corner_rms_px, 0.0);
    EXPECT_LT(calibrate.response.corner_rms_px, 1.0);
    const std::string result = io::read_file(calibrate.response.calibration_file);
    EXPECT_NE(result.find("rms_px"), std::string::npos) << result;
    SaveSamples save;
    save.request.path = test::scratch_directory() + "/corners_samples.yaml";
    ASSERT_TRUE(test::call(kNs + "save_samples", save));
    ASSERT_TRUE(save.response.success) << save.response.message;
    const SampleSet saved = io::read_samples(save.request.path);
    ASSERT_FALSE(saved.samples.empty());
    for (const PoseSample& sample : saved.samples) {
      ASSERT_TRUE(sample.corners);
      EXPECT_EQ(sample.corners->points.image.size(), sample.corners->points.object.size());
      EXPECT_GT(sample.corners->camera.K(0, 0), 0.0);
    }
  }
  ASSERT_TRUE(test::wait_for([&] { return rig.pattern_received; }, 5.0));
  EXPECT_EQ(calibrate.response.pattern.header.frame_id, rig.pattern.header.frame_id);
  const PoseWithCovariance Y = conversions::to_core(calibrate.response.pattern.pose);
  const Vector6d y_error = pose_error(Y.pose, conversions::to_eigen(rig.pattern.pose));
  const double y_nees = y_error.dot(Y.covariance.ldlt().solve(y_error));
  std::printf("Y: NEES %.2f, error %.3f mm / %.4f deg\n", y_nees, y_error.head<3>().norm() * 1e3,
              y_error.tail<3>().norm() * 180.0 / M_PI);
  EXPECT_LT(y_nees, bound) << "error " << y_error.transpose();
  EXPECT_GT(X.covariance.trace(), 0.0);

  // The latched message, the TF and the file say the same (the message of this /calibrate: a
  // calibration saved by an earlier run was published at start-up).
  ASSERT_TRUE(test::wait_for(
      [&] { return have_published && published.header.stamp == calibrate.response.calibration.header.stamp; }, 5.0));
  EXPECT_LE((conversions::to_eigen(published.pose.pose).matrix() - X.pose.matrix()).norm(), 1e-9);
  tf2_ros::Buffer buffer;
  tf2_ros::TransformListener listener(buffer);
  ASSERT_TRUE(test::wait_for([&] { return buffer.canTransform(kParent, "camera_optical_frame", ros::Time(0)); }, 5.0));
  const Eigen::Isometry3d tf = conversions::to_eigen(buffer.lookupTransform(kParent, "camera_optical_frame", ros::Time(0)).transform);
  EXPECT_LE((tf.matrix() - X.pose.matrix()).norm(), 1e-9);
  const io::CalibrationFile file = io::read_result(calibrate.response.calibration_file);
  EXPECT_LE((file.T_parent_camera().pose.matrix() - X.pose.matrix()).norm(), 1e-12);
  EXPECT_LE((file.T_parent_camera().covariance - X.covariance).norm(), 1e-18);

  // Next-best pose: ~status names one, /suggest_pose ranks and plans.
  EXPECT_TRUE(status.latest.has_suggestion) << status.latest.last_event;
  EXPECT_EQ(status.latest.next_pose.header.frame_id, "base_link");
  EXPECT_LT(status.latest.next_pose_object_error_mm, status.latest.object_error_mm);
  SuggestPose suggest;
  suggest.request.count = 5;
  suggest.request.target_mm = 0.7 * status.latest.object_error_mm;
  ASSERT_TRUE(test::call(kNs + "suggest_pose", suggest));
  ASSERT_TRUE(suggest.response.success) << suggest.response.message;
  ASSERT_EQ(suggest.response.poses.size(), 5u);
  for (std::size_t i = 0; i < 5; ++i) {
    EXPECT_EQ(suggest.response.poses[i].header.frame_id, "base_link");
    EXPECT_LT(suggest.response.predicted_object_error_mm[i], suggest.response.current_object_error_mm);
    if (i > 0) {
      EXPECT_GE(suggest.response.predicted_object_error_mm[i], suggest.response.predicted_object_error_mm[i - 1]);
    }
  }
  EXPECT_GT(suggest.response.poses_to_target, 0) << suggest.response.message;
  EXPECT_EQ(static_cast<int>(suggest.response.plan.size()), suggest.response.poses_to_target);
  std::printf("suggest_pose: object 1 sigma %.3f mm now, %.3f mm after the best pose; %s\n",
              suggest.response.current_object_error_mm, suggest.response.predicted_object_error_mm[0],
              suggest.response.message.c_str());
  SuggestPose bad;
  bad.request.criterion = "trace";
  ASSERT_TRUE(test::call(kNs + "suggest_pose", bad));
  EXPECT_FALSE(bad.response.success);
  EXPECT_NE(bad.response.message.find("unknown criterion"), std::string::npos) << bad.response.message;

  // Services, including bad input.
  ListSamples list;
  ASSERT_TRUE(test::call(kNs + "list_samples", list));
  const int n = list.response.samples;
  EXPECT_EQ(static_cast<int>(list.response.effector_poses.size()), n);

  RemoveSample remove;
  remove.request.index = 999;
  ASSERT_TRUE(test::call(kNs + "remove_sample", remove));
  EXPECT_FALSE(remove.response.success);
  EXPECT_NE(remove.response.message.find("valid indices"), std::string::npos) << remove.response.message;
  remove.request.index = -1;
  ASSERT_TRUE(test::call(kNs + "remove_sample", remove));
  EXPECT_FALSE(remove.response.success);
  EXPECT_EQ(remove.response.samples, n);

  SaveSamples save;
  save.request.path = test::scratch_directory() + "/saved_samples.yaml";
  ASSERT_TRUE(test::call(kNs + "save_samples", save));
  ASSERT_TRUE(save.response.success) << save.response.message;

  remove.request.index = 0;
  ASSERT_TRUE(test::call(kNs + "remove_sample", remove));
  EXPECT_TRUE(remove.response.success);
  EXPECT_EQ(remove.response.samples, n - 1);

  Reset reset;
  ASSERT_TRUE(test::call(kNs + "reset", reset));
  Calibrate too_few;
  ASSERT_TRUE(test::call(kNs + "calibrate", too_few));
  EXPECT_FALSE(too_few.response.success);
  EXPECT_NE(too_few.response.message.find("TooFewMotions"), std::string::npos) << too_few.response.message;
  SuggestPose none;
  ASSERT_TRUE(test::call(kNs + "suggest_pose", none));
  EXPECT_FALSE(none.response.success);
  EXPECT_NE(none.response.message.find("no estimate yet"), std::string::npos) << none.response.message;

  LoadSamples missing;
  missing.request.path = "/nonexistent/samples.yaml";
  ASSERT_TRUE(test::call(kNs + "load_samples", missing));
  EXPECT_FALSE(missing.response.success);
  EXPECT_NE(missing.response.message.find("IoError"), std::string::npos) << missing.response.message;

  LoadSamples load;
  load.request.path = save.request.path;
  ASSERT_TRUE(test::call(kNs + "load_samples", load));
  ASSERT_TRUE(load.response.success) << load.response.message;
  EXPECT_EQ(load.response.samples, n);
  Calibrate again;
  ASSERT_TRUE(test::call(kNs + "calibrate", again));
  ASSERT_TRUE(again.response.success) << again.response.message;
  EXPECT_LE((conversions::to_eigen(again.response.calibration.pose.pose).matrix() - X.pose.matrix()).norm(), 1e-9)
      << "save/load round trip changed the result";

  // A wrong detection (sample 3 paired with sample 0's pattern pose) is left out
  // and named in the response and in ~status.
  ASSERT_EQ(test::load_with_wrong_detection(kNs, save.request.path), n);
  Calibrate with_outlier;
  ASSERT_TRUE(test::call(kNs + "calibrate", with_outlier));
  ASSERT_TRUE(with_outlier.response.success) << with_outlier.response.message;
  ASSERT_EQ(with_outlier.response.rejected_samples.size(), 1u);
  EXPECT_EQ(with_outlier.response.rejected_samples[0], 3);
  EXPECT_NE(with_outlier.response.rejected_reasons[0].find("A X = X B"), std::string::npos)
      << with_outlier.response.rejected_reasons[0];
  EXPECT_TRUE(test::wait_for([&] { return status.latest.rejected_samples.size() == 1; }, 5.0));
  EXPECT_LE((conversions::to_eigen(with_outlier.response.calibration.pose.pose).translation() - X.pose.translation()).norm(),
            3.0 * std::sqrt(X.covariance.topLeftCorner<3, 3>().trace()))
      << "the outlier moved X";
  ASSERT_TRUE(test::call(kNs + "load_samples", load));  // back to the real session

  // Manual sampling: once the robot stands still (at most ~2 s away), one sample
  // may be taken; the same pose a second time is refused as a near duplicate.
  // A call that fails in transport while polling is retried, counted and printed:
  // a clean-clone run saw one (ArUco variant, 2026-11-23; no exception in the node,
  // the next call succeeded; not reproduced in 3 reruns).
  TakeSample take;
  int transport_failures = 0;
  ASSERT_TRUE(ros::service::waitForService(kNs + "take_sample", ros::Duration(20.0)));
  ASSERT_TRUE(test::wait_for(
      [&] {
        take = TakeSample();
        if (!ros::service::call(kNs + "take_sample", take)) {
          ++transport_failures;
          return false;
        }
        // Refused while moving or before fresh data; then taken, or refused as too close.
        return take.response.success || take.response.message.find("too close") != std::string::npos;
      },
      30.0))
      << take.response.message << " (" << transport_failures << " call(s) failed in transport)";
  if (transport_failures > 0) std::printf("take_sample: %d call(s) failed in transport and were retried\n", transport_failures);
  EXPECT_LE(transport_failures, 2);
  TakeSample again_same_pose;
  ASSERT_TRUE(test::call(kNs + "take_sample", again_same_pose));
  EXPECT_FALSE(again_same_pose.response.success);
  EXPECT_NE(again_same_pose.response.message.find("too close"), std::string::npos) << again_same_pose.response.message;

  SaveCalibration save_calibration;
  save_calibration.request.path = test::scratch_directory() + "/explicit.yaml";
  ASSERT_TRUE(test::call(kNs + "save_calibration", save_calibration));
  EXPECT_TRUE(save_calibration.response.success) << save_calibration.response.message;
  EXPECT_TRUE(std::filesystem::exists(save_calibration.request.path));
  EXPECT_TRUE(save_calibration.response.report.empty());  // none asked for

  // With a report directory, the node writes `handeye report`'s page of the samples
  // it calibrated (joint only: a corners report re-solves each half from the corners,
  // minutes here, and its page is the same code).
  if (kMethod == "joint") {
    SaveCalibration with_report;
    with_report.request.path = test::scratch_directory() + "/with_report.yaml";
    with_report.request.report_directory = test::scratch_directory() + "/report";
    ASSERT_TRUE(test::call(kNs + "save_calibration", with_report));
    EXPECT_TRUE(with_report.response.success) << with_report.response.message;
    EXPECT_EQ(with_report.response.report, with_report.request.report_directory + "/report.html")
        << with_report.response.message;
    for (const char* file : {"report.html", "report.yaml", "calibration.yaml", "residuals.png", "checks.png"}) {
      EXPECT_TRUE(std::filesystem::exists(with_report.request.report_directory + "/" + file)) << file;
    }
    const YAML::Node report = YAML::LoadFile(with_report.request.report_directory + "/report.yaml");
    // The samples of the last /calibrate: the session with the wrong detection at 3.
    EXPECT_EQ(report["samples"].size(), static_cast<std::size_t>(n));
    EXPECT_TRUE(report["samples"][3]["rejected"].as<bool>());
    EXPECT_EQ(report["advice"][0].as<std::string>().rfind("sample 3 is ", 0), 0u) << report["advice"][0];
    EXPECT_NE(report["source"].as<std::string>().find("/save_calibration"), std::string::npos);
  }
}

}  // namespace
}  // namespace handeye

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_calibration_node");
  ros::NodeHandle nh, pn("~");
  handeye::kNs = pn.param<std::string>("namespace", "/test_eye_on_hand/");
  handeye::kParent = pn.param<std::string>("parent_frame", "tool0");
  handeye::kNoiseOrigin = pn.param<std::string>("noise_origin", "estimated_from_residuals");
  handeye::kMethod = pn.param<std::string>("method", "joint");
  return RUN_ALL_TESTS();
}
