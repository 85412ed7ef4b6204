// Client of camera_tree.test: a camera driver publishes camera_link ->
// camera_optical_frame, the detector stamps its detections (and their
// depth-heavy covariance) in camera_link, and X is for the optical frame.
//  - The covariance moves with the pose: X's 6-dof NEES against the rig's truth
//    stays below chi2(6)'s 99.9% quantile (before, the depth variance stayed on
//    camera_link's x axis, i.e. the optical x: X was overconfident in depth).
//  - /calibrate publishes X above the camera's own tree (tool0 -> camera_link),
//    so every frame keeps one parent, again on a second /calibrate.
//  - Detections in camera_link are still accepted afterwards.
#include <geometry_msgs/PoseStamped.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include <boost/math/distributions/chi_squared.hpp>
#include <cstdio>

#include "handeye_covariance/simulation/monte_carlo.h"
#include "handeye_covariance/ros/msg_conversion.h"
#include "node_test_helpers.h"

namespace handeye {
namespace {

const std::string kNs = "/tree_eye_on_hand/";

TEST(CameraTree, DetectionsInCameraLinkGiveAnHonestXAndOneTfTree) {
  ros::NodeHandle nh;
  test::TruthWatcher rig;
  test::StatusWatcher status(kNs + "handeye_calibration/status");
  ASSERT_TRUE(test::wait_for([&] { return rig.received; }, 20.0)) << "no truth from the rig";
  ASSERT_TRUE(test::wait_for(
      [&] {
        return status.received && status.latest.samples >= 12 && status.latest.estimate_samples == status.latest.samples;
      },
      60.0))
      << "samples: " << status.latest.samples << ", last event: " << status.latest.last_event;

  Calibrate calibrate;
  ASSERT_TRUE(test::call(kNs + "calibrate", calibrate));
  ASSERT_TRUE(calibrate.response.success) << calibrate.response.message;
  EXPECT_EQ(calibrate.response.noise_origin, "given");  // the detections' covariances
  EXPECT_EQ(calibrate.response.published_tf, "tool0 -> camera_link");

  const PoseWithCovariance X = conversions::to_core(calibrate.response.calibration.pose);
  const Eigen::Isometry3d true_X = conversions::to_eigen(rig.truth.pose);
  const Vector6d error = pose_error(X.pose, true_X);
  const double nees = error.dot(X.covariance.ldlt().solve(error));
  const double bound = boost::math::quantile(boost::math::chi_squared(6.0), 0.999);
  std::printf("X from %d samples in camera_link: NEES %.2f (99.9%% bound %.1f), error %.3f mm / %.4f deg, "
              "sigma x y z %.3f %.3f %.3f mm\n",
              calibrate.response.samples_used, nees, bound, error.head<3>().norm() * 1e3,
              error.tail<3>().norm() * 180.0 / M_PI, std::sqrt(X.covariance(0, 0)) * 1e3,
              std::sqrt(X.covariance(1, 1)) * 1e3, std::sqrt(X.covariance(2, 2)) * 1e3);
  EXPECT_LT(nees, bound) << "error " << error.transpose();
  std::printf("chi2/dof: rotation %.2f, translation %.2f\n", calibrate.response.rotation_chi2_per_dof,
              calibrate.response.translation_chi2_per_dof);
  // The residuals agree with the stated covariances, and no clean sample looks like an outlier.
  // (With the covariance left in camera_link's axes, seed 3 gave NEES 46.9 and chi2/dof 3.56;
  // seeds 4 and 5 gave chi2/dof 3.20, and NEES 28.7 with 3 samples rejected.)
  EXPECT_LT(calibrate.response.translation_chi2_per_dof, 2.5);  // 0.78-1.88 over 8 runs here
  EXPECT_TRUE(calibrate.response.rejected_samples.empty()) << calibrate.response.rejected_samples.size() << " rejected";

  // One tree: the driver's camera_link -> optical edge stays, X hangs camera_link off tool0,
  // and the chain tool0 -> optical frame is X.
  tf2_ros::Buffer buffer;
  tf2_ros::TransformListener listener(buffer);
  ASSERT_TRUE(test::wait_for([&] { return buffer.canTransform("base_link", "camera_optical_frame", ros::Time(0)); }, 5.0))
      << "the camera's tree is not connected to the robot's";
  std::string parent;
  ASSERT_TRUE(buffer._getParent("camera_optical_frame", ros::Time(0), parent));
  EXPECT_EQ(parent, "camera_link");
  ASSERT_TRUE(buffer._getParent("camera_link", ros::Time(0), parent));
  EXPECT_EQ(parent, "tool0");
  const Eigen::Isometry3d chain =
      conversions::to_eigen(buffer.lookupTransform("tool0", "camera_optical_frame", ros::Time(0)).transform);
  EXPECT_LE((chain.matrix() - X.pose.matrix()).norm(), 1e-9);

  // A second /calibrate finds its own edge and replaces it (no "already connected").
  Calibrate again;
  ASSERT_TRUE(test::call(kNs + "calibrate", again));
  ASSERT_TRUE(again.response.success) << again.response.message;
  EXPECT_EQ(again.response.published_tf, "tool0 -> camera_link");

  // Detections in camera_link are still accepted with the tree connected: after
  // /reset, the robot standing at its last pose gives a new sample.
  Reset reset;
  ASSERT_TRUE(test::call(kNs + "reset", reset));
  EXPECT_TRUE(test::wait_for([&] { return status.latest.samples == 1; }, 15.0))
      << "no sample after /reset; last event: " << status.latest.last_event;
  EXPECT_EQ(status.latest.last_event.find("refused"), std::string::npos) << status.latest.last_event;
}

}  // namespace
}  // namespace handeye

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_camera_tree");
  return RUN_ALL_TESTS();
}
