// The node fed by `rosbag play --clock` must take the very samples that the
// offline replay takes from the same bag, and give the same X.
#include <rosgraph_msgs/Clock.h>

#include "handeye_covariance/estimation/estimator.h"
#include "handeye_covariance/ros/bag.h"
#include "handeye_covariance/ros/msg_conversion.h"
#include "node_test_helpers.h"

namespace handeye {
namespace {

std::string bag_path;

TEST(CalibrationNode, RosbagPlayGivesTheSameSamplesAsTheOfflineReplay) {
  SessionConfig config;
  config.tag_ids = {0};
  SessionSettings settings = session_settings(config);
  settings.session_file.clear();
  CalibrationSession session(settings);  // the node's own session class, offline
  const BagReplay offline = replay_bag(bag_path, config, session);
  const Calibration expected = session.calibrate(session.snapshot());

  test::StatusWatcher status("/play_eye_on_hand/handeye_calibration/status");
  ASSERT_TRUE(test::wait_for(
      [&] { return status.received && status.latest.samples >= static_cast<int>(offline.samples.samples.size()); },
      120.0))
      << "node has " << status.latest.samples << " samples, offline " << offline.samples.samples.size()
      << "; last event: " << status.latest.last_event;

  ListSamples list;
  ASSERT_TRUE(test::call("/play_eye_on_hand/list_samples", list));
  ASSERT_EQ(list.response.stamps.size(), offline.samples.samples.size());
  for (std::size_t i = 0; i < list.response.stamps.size(); ++i) {
    EXPECT_NEAR(list.response.stamps[i], *offline.samples.samples[i].stamp, 1e-6) << "sample " << i;
  }
  Calibrate calibrate;
  ASSERT_TRUE(test::call("/play_eye_on_hand/calibrate", calibrate));
  ASSERT_TRUE(calibrate.response.success) << calibrate.response.message;
  const PoseWithCovariance X = conversions::to_core(calibrate.response.calibration.pose);
  EXPECT_LE((X.pose.matrix() - expected.T_parent_camera.matrix()).norm(), 1e-9);
  EXPECT_LE((X.covariance - expected.pose_covariance).norm(), 1e-9 * expected.pose_covariance.norm());
  EXPECT_EQ(calibrate.response.noise_origin, "given");  // the detections carry their covariance
}

}  // namespace
}  // namespace handeye

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_bag_play");
  ros::NodeHandle nh, pn("~");
  handeye::bag_path = pn.param<std::string>("bag", "");
  return RUN_ALL_TESTS();
}
