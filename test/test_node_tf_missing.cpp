#include "node_test_helpers.h"

namespace handeye {
namespace {

const std::string kNs = "/notf_eye_on_hand/";

TEST(CalibrationNode, MissingRobotTfRefusesSamplesWithTheReason) {
  test::StatusWatcher status(kNs + "handeye_calibration/status");
  ASSERT_TRUE(test::wait_for(
      [&] { return status.received && status.latest.last_event.find("no TF") != std::string::npos; }, 20.0))
      << "last event: " << status.latest.last_event;
  EXPECT_NE(status.latest.last_event.find("base_link -> tool0"), std::string::npos) << status.latest.last_event;
  EXPECT_EQ(status.latest.samples, 0);

  TakeSample take;
  ASSERT_TRUE(test::call(kNs + "take_sample", take));
  EXPECT_FALSE(take.response.success);
  EXPECT_NE(take.response.message.find("no stamp-matched observation"), std::string::npos) << take.response.message;

  Calibrate calibrate;
  ASSERT_TRUE(test::call(kNs + "calibrate", calibrate));
  EXPECT_FALSE(calibrate.response.success);
  EXPECT_NE(calibrate.response.message.find("TooFewMotions"), std::string::npos) << calibrate.response.message;
}

}  // namespace
}  // namespace handeye

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_tf_missing");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
