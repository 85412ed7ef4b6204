// Publishes a calibration with a strongly anisotropic covariance to a real rviz
// (test/rviz_display_closeup.rviz), takes a screenshot, and checks that our display
// drew the position ellipsoid: a magenta region of plausible size whose
// long/short axis ratio matches the sigma ratio. Fails if the plugin did not
// load or drew nothing. The screenshot is kept as a test artifact.
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <tf2_ros/static_transform_broadcaster.h>

#include <cstdio>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "handeye_covariance/ros/msg_conversion.h"
#include "node_test_helpers.h"

namespace handeye {
namespace {

std::string artifact_dir;

/// The process id of this launch's /rviz node, from its own master ("" when none): the launch
/// respawns an rviz that dies at start-up, so the test checks that the one that drew is the
/// one that draws at the end.
std::string rviz_pid() {
  std::string out;
  if (FILE* pipe = popen("rosnode info /rviz 2>/dev/null", "r")) {
    char buffer[256];
    while (fgets(buffer, sizeof buffer, pipe)) {
      const std::string line(buffer);
      if (line.rfind("Pid: ", 0) == 0) out = line.substr(5);
    }
    pclose(pipe);
  }
  while (!out.empty() && (out.back() == '\n' || out.back() == ' ')) out.pop_back();
  return out;
}

struct Blob {
  double area = 0, major = 0, minor = 0;  // pixels; axes from second moments
};

/// Our display's default position colour: magenta (OpenCV hue ~150 of 180).
Blob magenta_blob(const std::string& png) {
  const cv::Mat image = cv::imread(png, cv::IMREAD_COLOR);
  if (image.empty()) return {};
  cv::Mat hsv, mask;
  cv::cvtColor(image, hsv, cv::COLOR_BGR2HSV);
  cv::inRange(hsv, cv::Scalar(140, 80, 60), cv::Scalar(160, 255, 255), mask);
  // TF axes and frame names drawn across the ellipsoid cut it; close those gaps,
  // then keep the largest region (other magenta, e.g. a panel icon, is elsewhere).
  cv::morphologyEx(mask, mask, cv::MORPH_CLOSE, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(13, 13)));
  cv::Mat labels, stats, centroids;
  const int n = cv::connectedComponentsWithStats(mask, labels, stats, centroids);
  int largest = 0;
  for (int i = 1; i < n; ++i) {
    if (largest == 0 || stats.at<int>(i, cv::CC_STAT_AREA) > stats.at<int>(largest, cv::CC_STAT_AREA)) largest = i;
  }
  if (largest == 0) return {};
  const cv::Moments m = cv::moments(labels == largest, true);
  Blob blob;
  blob.area = m.m00;
  if (m.m00 < 1) return blob;
  // Second central moments: an ellipse with semi-axes a, b has eigenvalues a^2/4, b^2/4.
  const double xx = m.mu20 / m.m00, yy = m.mu02 / m.m00, xy = m.mu11 / m.m00;
  const double mean = 0.5 * (xx + yy), spread = std::sqrt(0.25 * (xx - yy) * (xx - yy) + xy * xy);
  blob.major = 2.0 * std::sqrt(mean + spread);
  blob.minor = 2.0 * std::sqrt(std::max(0.0, mean - spread));
  return blob;
}

TEST(RvizDisplay, DrawsTheAnisotropicPositionEllipsoid) {
  ASSERT_NE(std::getenv("DISPLAY"), nullptr) << "no X display: run under ./scripts/test (it starts Xvfb)";
  ros::NodeHandle nh;
  tf2_ros::StaticTransformBroadcaster static_tf;
  // base_link == tool0 here; the camera sits 5 cm above, and the view follows it.
  const Eigen::Isometry3d X = se3::make_pose(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0.0, 0.0, 0.05));
  geometry_msgs::TransformStamped base_tool, tool_camera;
  base_tool.header.frame_id = "base_link";
  base_tool.child_frame_id = "tool0";
  base_tool.transform.rotation.w = 1.0;
  tool_camera.header.frame_id = "tool0";
  tool_camera.child_frame_id = "camera_optical_frame";
  tool_camera.transform = conversions::to_transform_msg(X);
  base_tool.header.stamp = tool_camera.header.stamp = ros::Time::now();
  static_tf.sendTransform({base_tool, tool_camera});

  // sigma_x = 1 mm, sigma_y = 0.25 mm: the drawn ellipse must be 4 times longer than wide.
  PoseWithCovariance calibration{X, Matrix6d::Zero()};
  calibration.covariance.diagonal() << 1e-6, 0.0625e-6, 0.0625e-6, 1e-10, 1e-10, 1e-10;
  geometry_msgs::PoseWithCovarianceStamped msg;
  msg.header.frame_id = "tool0";
  msg.pose = conversions::to_msg(calibration);
  ros::Publisher pub = nh.advertise<geometry_msgs::PoseWithCovarianceStamped>(
      "/handeye_eye_on_hand/handeye_calibration/estimate", 1, true);

  std::filesystem::create_directories(artifact_dir);
  const std::string png = artifact_dir + "/rviz_screenshot.png";
  const std::string capture = "import -window root " + png + " 2>/dev/null";
  Blob blob;
  // rviz takes a while to start under software GL; retry until our colour shows.
  test::wait_for(
      [&] {
        msg.header.stamp = ros::Time::now();
        pub.publish(msg);
        ros::WallDuration(1.0).sleep();
        if (std::system(capture.c_str()) != 0) return false;
        blob = magenta_blob(png);
        return blob.area > 500;
      },
      90.0);
  std::printf("[rviz] magenta area %.0f px, axes %.1f x %.1f px, ratio %.2f (sigma ratio 4); screenshot %s\n", blob.area,
              blob.major, blob.minor, blob.minor > 0 ? blob.major / blob.minor : 0.0, png.c_str());
  ASSERT_GT(blob.area, 2000) << "no ellipsoid drawn: did the plugin load? see " << png;
  const std::string drew = rviz_pid();
  ASSERT_FALSE(drew.empty()) << "rviz drew, but rosnode info /rviz gives no pid";
  const cv::Mat image = cv::imread(png);
  EXPECT_LT(blob.area, 0.25 * image.rows * image.cols) << "the ellipsoid fills the view";
  ASSERT_GT(blob.minor, 0.0);
  EXPECT_NEAR(blob.major / blob.minor, 4.0, 1.0) << "long/short axis ratio should follow the sigma ratio";

  // A covariance that is not positive semi-definite: nothing drawn (a status
  // error in the display), and rviz survives to draw the next valid one.
  geometry_msgs::PoseWithCovarianceStamped invalid = msg;
  invalid.pose.covariance[7] = -1e-6;  // (y, y) < 0
  const auto shows = [&](const geometry_msgs::PoseWithCovarianceStamped& m, bool expect_drawn) {
    return test::wait_for(
        [&] {
          pub.publish(m);
          ros::WallDuration(1.0).sleep();
          if (std::system(capture.c_str()) != 0) return false;
          return (magenta_blob(png).area > 2000) == expect_drawn;
        },
        20.0);
  };
  EXPECT_TRUE(shows(invalid, false)) << "an invalid covariance was drawn";
  EXPECT_TRUE(shows(msg, true)) << "rviz did not draw again after an invalid covariance (crashed?)";
  EXPECT_EQ(rviz_pid(), drew) << "rviz died after the invalid covariance and was started again";
}

}  // namespace
}  // namespace handeye

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_rviz_screenshot");
  ros::NodeHandle nh, pn("~");
  handeye::artifact_dir = pn.param<std::string>("artifact_dir", "/tmp");
  // rviz is up already (the launch file starts it), under any window the panel test opens
  // while this waits; that window is gone when the lock comes.
  handeye::test::DisplayLock display;
  return RUN_ALL_TESTS();
}
