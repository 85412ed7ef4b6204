// Client of readme_commands.test: the ROS commands of the README, docs/ros.md and docs/checking.md (`rostopic echo`,
// `rosservice call`) run as a user types them, in a shell, against the simulated
// rig. They need Python's message modules for this package's types and for
// geometry_msgs (scripts/setup installs them); without, rostopic prints
// "Cannot load message class for [handeye_covariance/CalibrationStatus]".
#include <sys/wait.h>

#include <cstdio>
#include <cstdlib>
#include <string>

#include "handeye_covariance/io/yaml_io.h"
#include "node_test_helpers.h"

namespace handeye {
namespace {

struct Shell {
  int exit_code = -1;
  std::string output;  // stdout and stderr
};

Shell shell(const std::string& command) {
  const std::string file = ::testing::TempDir() + "/readme_command_output";
  const int status = std::system((command + " >" + file + " 2>&1").c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, io::read_file(file)};
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

TEST(ReadmeCommands, StatusEchoAndCalibrateCallWorkAsTyped) {
  const std::string ns = "/handeye_eye_on_hand";
  const Shell echo = shell("timeout 30 rostopic echo -n 1 " + ns + "/handeye_calibration/status");
  ASSERT_EQ(echo.exit_code, 0) << echo.output;
  EXPECT_FALSE(contains(echo.output, "Cannot load message class")) << echo.output;
  EXPECT_TRUE(contains(echo.output, "samples_needed: 3")) << echo.output;
  EXPECT_TRUE(contains(echo.output, "parent_frame: \"tool0\"")) << echo.output;

  test::StatusWatcher status(ns + "/handeye_calibration/status");
  ASSERT_TRUE(test::wait_for([&] { return status.latest.samples >= 5 && status.latest.has_estimate; }, 60.0))
      << status.latest.samples << " samples; " << status.latest.last_event;

  const Shell call = shell("timeout 30 rosservice call " + ns + "/calibrate");
  ASSERT_EQ(call.exit_code, 0) << call.output;
  EXPECT_TRUE(contains(call.output, "success: True")) << call.output;
  EXPECT_TRUE(contains(call.output, "X = T_tool0_camera_optical_frame")) << call.output;
  EXPECT_TRUE(contains(call.output, "frame_id: \"tool0\"")) << call.output;
  EXPECT_TRUE(contains(call.output, "published_tf: \"tool0 -> camera_optical_frame\"")) << call.output;

  // The latched result, and a service with arguments as docs/ros.md writes them.
  const Shell calibration = shell("timeout 30 rostopic echo -n 1 " + ns + "/handeye_calibration/calibration");
  ASSERT_EQ(calibration.exit_code, 0) << calibration.output;
  EXPECT_TRUE(contains(calibration.output, "covariance: [")) << calibration.output;
  const Shell suggest = shell("timeout 60 rosservice call " + ns + "/suggest_pose \"{count: 3, target_mm: 0.5}\"");
  ASSERT_EQ(suggest.exit_code, 0) << suggest.output;
  EXPECT_TRUE(contains(suggest.output, "success: True")) << suggest.output;
  EXPECT_TRUE(contains(suggest.output, "predicted_object_error_mm: [")) << suggest.output;

  // The report, as docs/offline.md asks the node for one (into this test's own directory).
  const std::string dir = test::scratch_directory();
  const Shell save = shell("timeout 60 rosservice call " + ns + "/save_calibration \"{path: '" + dir +
                           "/calibration.yaml', report_directory: '" + dir + "/report'}\"");
  ASSERT_EQ(save.exit_code, 0) << save.output;
  EXPECT_TRUE(contains(save.output, "success: True")) << save.output;
  EXPECT_TRUE(contains(save.output, "report: \"" + dir + "/report/report.html\"")) << save.output;
  EXPECT_TRUE(std::filesystem::exists(dir + "/report/residuals.png")) << save.output;

  // "Check a calibration later", in the node: start a check, its state on ~check, cancel it.
  const Shell check = shell("timeout 30 rosservice call " + ns + "/check_calibration \"{views: 5}\"");
  ASSERT_EQ(check.exit_code, 0) << check.output;
  EXPECT_TRUE(contains(check.output, "success: True")) << check.output;
  const Shell state = shell("timeout 30 rostopic echo -n 1 " + ns + "/handeye_calibration/check");
  ASSERT_EQ(state.exit_code, 0) << state.output;
  EXPECT_FALSE(contains(state.output, "Cannot load message class")) << state.output;
  EXPECT_TRUE(contains(state.output, "state: \"collecting\"")) << state.output;
  const Shell cancel = shell("timeout 30 rosservice call " + ns + "/check_calibration \"{cancel: true}\"");
  ASSERT_EQ(cancel.exit_code, 0) << cancel.output;
  EXPECT_TRUE(contains(cancel.output, "success: True")) << cancel.output;
}

}  // namespace
}  // namespace handeye

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_readme_commands");
  return RUN_ALL_TESTS();
}
