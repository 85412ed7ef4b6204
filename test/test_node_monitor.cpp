// Client of monitor.test: the monitor of publish.launch monitor:=true (ros/calibration_monitor_node.h)
// against the simulated rig, whose frames are not the defaults, eye-in-hand or (eye_on_hand:=false)
// eye-to-hand. The test writes a calibration of the rig (20 simulated views of its truth, the rig's
// detection noise, solved as `handeye solve` does), starts publish.launch monitor:=true in a shell as a
// user types it, and watches /diagnostics: no ERROR over ~views still views; after the rig's camera
// moves 3 mm on its mount, ERROR within 10 still views, and X named on ~check once the window holds
// only views after the bump, its reported change the bump within its covariance (NEES below chi2(6)'s
// 99.9%). The published TF stays the saved X throughout.
#include <diagnostic_msgs/DiagnosticArray.h>
#include <signal.h>
#include <std_msgs/Float64.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include <cstdio>
#include <filesystem>

#include "handeye_covariance/core/lie.h"
#include "handeye_covariance/core/pose_covariance.h"
#include "handeye_covariance/core/statistics.h"
#include "handeye_covariance/core/units.h"
#include "handeye_covariance/io/yaml_io.h"
#include "handeye_covariance/ros/messages.h"
#include "handeye_covariance/ros/msg_conversion.h"
#include "handeye_covariance/session/calibration_session.h"
#include "handeye_covariance/simulation/simulation.h"
#include "node_test_helpers.h"

namespace handeye {
namespace {

// monitor.test's robot and camera frames, not the node's defaults: the monitor and the publisher
// take them from the file.
const std::string kBase = "panda_link0", kEffector = "panda_hand", kCamera = "camera_color_optical_frame";

/// A calibration of the simulated rig written to `file`: its truth, its detection noise (0.3 mm,
/// 0.05 deg, the robot exact), the noise estimated from the views, as `handeye solve` runs it.
void write_rig_calibration(Setup setup, const std::string& file) {
  Rng rng(11);
  MeasurementNoise noise;
  noise.camera.translation = std::pow(0.3e-3, 2) * Eigen::Matrix3d::Identity();
  noise.camera.rotation = std::pow(radians(0.05), 2) * Eigen::Matrix3d::Identity();
  SimulatedSession sim = simulate_session(rng, setup, typical_X(setup), 20, noise);
  sim.samples.noise.reset();
  sim.samples.rig.frames = {kBase, kEffector, kCamera, "tag_0"};  // monitor.test's rig
  CalibrationSession session(session_settings(sim.samples));
  session.replace(sim.samples.samples, "the rig's calibration");
  const Calibration c = session.calibrate_checked(session.snapshot());
  std::filesystem::create_directories(std::filesystem::path(file).parent_path());
  io::write_file_atomically(file, io::format_result(c, io::context_of(sim.samples)));
}

TEST(Monitor, NoErrorOverStillViewsAndErrorWithin10AfterABump) {
  ros::NodeHandle pn("~");
  const bool eye_on_hand = pn.param("eye_on_hand", true);
  const int views = pn.param("views", 200);
  const handeye::Setup setup = eye_on_hand ? handeye::Setup::EyeInHand : handeye::Setup::EyeToHand;
  // publish.launch's namespace, and a directory of this variant's own (ctest runs both at once).
  const std::string ns = eye_on_hand ? "/handeye_eye_on_hand" : "/handeye_eye_on_base";
  const std::string dir = "/tmp/handeye_covariance_rostest_monitor" + std::string(eye_on_hand ? "" : "_eye_on_base");
  const std::string file = dir + "/calibration.yaml";
  const std::string parent = eye_on_hand ? kEffector : kBase;  // X's parent
  write_rig_calibration(setup, file);
  const std::string launch = "roslaunch handeye_covariance publish.launch monitor:=true calibration_file:=" + file +
                             (eye_on_hand ? "" : " eye_on_hand:=false") + " still_window:=0.15 > " + dir +
                             "/launch.log 2>&1 & echo $! > " + dir + "/launch.pid";
  ASSERT_EQ(std::system(launch.c_str()), 0);

  ros::NodeHandle nh;
  diagnostic_msgs::DiagnosticStatus latest;
  int errors = 0;
  auto diagnostics = nh.subscribe<diagnostic_msgs::DiagnosticArray>("/diagnostics", 50, [&](const auto& msg) {
    for (const auto& s : msg->status) {
      if (s.name.find("calibration check") == std::string::npos) continue;
      latest = s;
      errors += s.level == diagnostic_msgs::DiagnosticStatus::ERROR;
    }
  });
  int checks = 0;
  CalibrationCheckMsg check;
  auto check_sub = nh.subscribe<CalibrationCheckMsg>(ns + "/handeye_monitor/check", 50,
                                                     [&](const auto& msg) {
                                                       check = *msg;
                                                       ++checks;
                                                     });
  ros::Publisher bump = nh.advertise<std_msgs::Float64>("/rig_simulator/bump_camera_mm", 1, true);
  tf2_ros::Buffer tf;
  tf2_ros::TransformListener listener(tf);

  // A check per still view once the window has 3: `views` of them with the rig unchanged.
  ASSERT_TRUE(test::wait_for([&] { return checks >= views; }, views + 20.0))
      << checks << " checks; last diagnostic: " << latest.message << " (see " << dir << "/launch.log)";
  EXPECT_EQ(errors, 0) << "an ERROR without a change: " << latest.message;
  std::printf("[monitor] %d checks of an unchanged rig: %d ERROR, last: %s\n", checks, errors, latest.message.c_str());
  // The published TF is the saved X (the monitor only reads).
  const Eigen::Isometry3d saved = io::read_result(file).T_parent_camera().pose;
  geometry_msgs::TransformStamped published;
  ASSERT_NO_THROW(published = tf.lookupTransform(parent, kCamera, ros::Time(0)));
  EXPECT_TRUE(conversions::to_eigen(published.transform).isApprox(saved, 1e-9));

  std_msgs::Float64 mm;
  mm.data = 3.0;
  bump.publish(mm);
  const int before = checks;
  ASSERT_TRUE(test::wait_for([&] { return latest.level == diagnostic_msgs::DiagnosticStatus::ERROR || checks >= before + 12; },
                             30.0));
  EXPECT_EQ(latest.level, diagnostic_msgs::DiagnosticStatus::ERROR) << latest.message;
  EXPECT_LE(checks - before, 10) << "still views until ERROR";
  std::printf("[monitor] the camera moved 3 mm: ERROR after %d still views: %s\n", checks - before,
              latest.message.c_str());
  // While the window straddles the bump no single rigid change explains all of it; once
  // its 10 views are all after it, the check names the camera's mount.
  const int error_at = checks;
  ASSERT_TRUE(test::wait_for([&] { return checks >= error_at + 10; }, 30.0));
  EXPECT_EQ(latest.level, diagnostic_msgs::DiagnosticStatus::ERROR) << latest.message;
  EXPECT_EQ(check.changed, "X") << check.text;
  std::printf("[monitor] 10 views later: %s\n", latest.message.c_str());
  // The change it reports is the bump: the rig moved the camera 3 mm along its own x axis
  // (rig_simulator.cpp), and the change is the package's pose perturbation from the saved X to
  // the new (pose_covariance.h: t = t_saved + change_t, R = exp(change_R) R_saved). Its NEES
  // under the reported covariance is one chi2(6) draw: below its 99.9% point (22.46) unless the
  // value or the covariance is wrong (a flipped sign puts it 6 mm off, hundreds of sigma).
  Eigen::Isometry3d bumped = typical_X(setup);
  bumped.translation() += bumped.linear() * Eigen::Vector3d(metres(3.0), 0.0, 0.0);
  const Vector6d expected = pose_error(bumped, saved);
  const Vector6d reported = Eigen::Map<const Vector6d>(check.change.data());
  const Matrix6d covariance = Eigen::Map<const Eigen::Matrix<double, 6, 6, Eigen::RowMajor>>(check.change_covariance.data());
  const Vector6d error = reported - expected;
  const double nees = error.dot(covariance.ldlt().solve(error));
  std::printf("[monitor] reported change %.2f, %.2f, %.2f mm (the bump: %.2f, %.2f, %.2f mm), NEES %.2f of 6\n",
              millimetres(reported(0)), millimetres(reported(1)), millimetres(reported(2)), millimetres(expected(0)),
              millimetres(expected(1)), millimetres(expected(2)), nees);
  EXPECT_LT(nees, chi2_quantile(6, 0.999)) << "reported " << reported.transpose() << ", the bump " << expected.transpose();
  ASSERT_NO_THROW(published = tf.lookupTransform(parent, kCamera, ros::Time(0)));
  EXPECT_TRUE(conversions::to_eigen(published.transform).isApprox(saved, 1e-9)) << "the monitor never changes the TF";

  std::system(("kill -INT $(cat " + dir + "/launch.pid)").c_str());
}

}  // namespace
}  // namespace handeye

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_monitor");
  return RUN_ALL_TESTS();
}
