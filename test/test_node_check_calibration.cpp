// Client of check_calibration.test: the node calibrates from the simulated rig, then
// checks that calibration from 5 new views taken as samples are (consistent), and again
// after the rig's camera moved 3 mm on its mount (changed: X, by about 3 mm). The
// session's samples are not touched by a check.
#include <std_msgs/Float64.h>

#include <filesystem>

#include "handeye_covariance/ros/messages.h"
#include "node_test_helpers.h"

namespace handeye {
namespace {

const std::string kNs = "/check_eye_on_hand/";

struct CheckWatcher {
  ros::Subscriber sub;
  CalibrationCheckMsg latest;
  int received = 0;
  explicit CheckWatcher(const std::string& topic) {
    ros::NodeHandle nh;
    sub = nh.subscribe<CalibrationCheckMsg>(topic, 10, [this](const auto& msg) {
      latest = *msg;
      ++received;
    });
  }
};

/// Starts a check of 5 views and waits for its verdict on ~check.
CalibrationCheckMsg check(CheckWatcher& watcher) {
  CheckCalibration srv;
  srv.request.views = 5;
  watcher.latest.state = "";  // the previous verdict is latched: wait for this one's
  EXPECT_TRUE(test::call(kNs + "check_calibration", srv));
  EXPECT_TRUE(srv.response.success) << srv.response.message;
  EXPECT_EQ(srv.response.check.state, "collecting") << srv.response.check.text;
  EXPECT_EQ(srv.response.check.views_needed, 5);
  EXPECT_TRUE(test::wait_for(
      [&] { return watcher.latest.state == "consistent" || watcher.latest.state == "changed"; }, 40.0))
      << watcher.latest.state << ": " << watcher.latest.text;
  return watcher.latest;
}

TEST(CheckCalibration, ChecksTheCalibrationFromNewViewsAndFindsAMovedCamera) {
  std::filesystem::remove("/tmp/handeye_covariance_rostest_check/calibration.yaml");
  ros::NodeHandle nh;
  test::StatusWatcher status(kNs + "handeye_calibration/status");
  CheckWatcher watcher(kNs + "handeye_calibration/check");
  ros::Publisher bump = nh.advertise<std_msgs::Float64>("/rig_simulator/bump_camera_mm", 1, true);

  // Nothing to check yet: refused with the reason.
  ASSERT_TRUE(test::wait_for([&] { return status.received; }, 20.0));
  CheckCalibration early;
  ASSERT_TRUE(test::call(kNs + "check_calibration", early));
  EXPECT_FALSE(early.response.success);
  EXPECT_NE(early.response.message.find("no calibration to check"), std::string::npos) << early.response.message;

  ASSERT_TRUE(test::wait_for([&] { return status.latest.samples >= 10; }, 60.0)) << status.latest.last_event;
  Calibrate calibrate;
  ASSERT_TRUE(test::call(kNs + "calibrate", calibrate));
  ASSERT_TRUE(calibrate.response.success) << calibrate.response.message;

  const int samples = status.latest.samples;
  const CalibrationCheckMsg same = check(watcher);
  EXPECT_EQ(same.state, "consistent") << same.text;
  EXPECT_GE(same.p_value, 0.01);
  EXPECT_EQ(same.view_error_mm.size(), 5u);
  EXPECT_EQ(same.view_sigma_mm.size(), 5u);
  for (double sigma : same.view_sigma_mm) EXPECT_GT(sigma, 0.0);
  // The check's views went to its own list; auto-sampling may have added one before it began.
  EXPECT_LE(status.latest.samples, samples + 1);

  std_msgs::Float64 mm;
  mm.data = 3.0;
  bump.publish(mm);
  ros::Duration(0.5).sleep();
  const CalibrationCheckMsg moved = check(watcher);
  EXPECT_EQ(moved.state, "changed") << moved.text;
  EXPECT_LT(moved.p_value, 0.01);
  EXPECT_EQ(moved.changed, "X") << moved.text;
  const double change_mm = std::sqrt(moved.change[0] * moved.change[0] + moved.change[1] * moved.change[1] +
                                     moved.change[2] * moved.change[2]) * 1e3;
  const double sigma_mm =
      std::sqrt(moved.change_covariance[0] + moved.change_covariance[7] + moved.change_covariance[14]) * 1e3;
  EXPECT_NEAR(change_mm, 3.0, 3.0 * sigma_mm) << moved.text;
  EXPECT_LE(status.latest.samples, samples + 1);

  CheckCalibration cancel;
  cancel.request.cancel = true;
  ASSERT_TRUE(test::call(kNs + "check_calibration", cancel));
  EXPECT_FALSE(cancel.response.success);  // nothing collecting
}

}  // namespace
}  // namespace handeye

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_check_calibration");
  return RUN_ALL_TESTS();
}
