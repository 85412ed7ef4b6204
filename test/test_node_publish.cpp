// Client of publish.test: publish.launch with our result file, easy_handeye's two
// formats, `inverse`, a corrupt, a missing and a contradicted file, and the
// calibration node publishing its saved calibration at start-up. Each case runs
// roslaunch as a user types it, with its own frame names.
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>

#include <filesystem>
#include <map>
#include <random>
#include <regex>
#include <sstream>

#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <tf2_msgs/TFMessage.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <tf2_ros/transform_listener.h>

#include "handeye_covariance/core/pose_covariance.h"
#include "handeye_covariance/io/yaml_io.h"
#include "handeye_covariance/ros/msg_conversion.h"
#include "easy_handeye_file.h"
#include "node_test_helpers.h"

extern char** environ;

namespace handeye {
namespace {


/// A roslaunch (or any command) running in the background, its output in a file;
/// interrupted (as Ctrl-C) when it goes out of scope.
class Launch {
 public:
  explicit Launch(std::vector<std::string> args, const std::string& name)
      : log_(test::scratch_directory() + "/" + name + ".log") {
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 1, log_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&actions, 1, 2);
    EXPECT_EQ(posix_spawnp(&pid_, argv[0], &actions, nullptr, argv.data(), environ), 0);
    posix_spawn_file_actions_destroy(&actions);
  }
  ~Launch() {
    if (pid_ <= 0) return;  // never started: kill(0) would signal the test itself
    if (!finished()) {
      kill(pid_, SIGINT);
      // roslaunch waits up to 15 s for its nodes before it escalates; killing it earlier leaves them running.
      test::wait_for([this] { return finished(); }, 25.0);
      if (!finished()) kill(pid_, SIGKILL), waitpid(pid_, &status_, 0);
    }
  }
  bool finished() {
    if (done_ || pid_ <= 0) return true;
    done_ = waitpid(pid_, &status_, WNOHANG) == pid_;
    return done_;
  }
  std::string output() const { return std::filesystem::exists(log_) ? io::read_file(log_) : ""; }

 private:
  std::string log_;
  pid_t pid_ = 0;
  int status_ = 0;
  bool done_ = false;
};

Launch publish(const std::string& name, const std::string& file, std::vector<std::string> extra = {}) {
  std::vector<std::string> args = {"roslaunch", "handeye_covariance", "publish.launch", "namespace_prefix:=" + name,
                                   "calibration_file:=" + file};
  args.insert(args.end(), extra.begin(), extra.end());
  return Launch(args, name);
}

io::ResultContext frames(Setup setup, const std::string& parent, const std::string& child) {
  io::ResultContext context;
  context.setup = setup;
  context.parent = parent;
  context.child = child;
  return context;
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

/// A seeded X with a full (correlated) covariance.
PoseWithCovariance random_calibration(std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  PoseWithCovariance X;
  X.pose = se3::exp((Vector6d() << 0.05 * n(rng), 0.05 * n(rng), 0.1 * n(rng), n(rng), n(rng), n(rng)).finished());
  Matrix6d A;
  for (int i = 0; i < 36; ++i) A(i / 6, i % 6) = n(rng);
  X.covariance = 1e-7 * (A * A.transpose() + Matrix6d::Identity());
  return X;
}

std::string write(const std::string& name, const std::string& text) {
  const std::string path = test::scratch_directory() + "/" + name;
  io::write_file_atomically(path, text);
  return path;
}

struct Fixture : ::testing::Test {
  tf2_ros::Buffer tf;
  tf2_ros::TransformListener listener{tf};
  /// Each node's latest /tf_static message: the edges it latches now (an edge it withdrew is gone).
  std::map<std::string, std::vector<geometry_msgs::TransformStamped>> static_edges;
  ros::Subscriber static_sub;

  Fixture() {
    ros::NodeHandle nh;
    static_sub = nh.subscribe<tf2_msgs::TFMessage>(
        "/tf_static", 20, [this](const ros::MessageEvent<tf2_msgs::TFMessage const>& event) {
          static_edges[event.getPublisherName()] = event.getMessage()->transforms;
        });
  }

  /// T_parent_child from TF, once it can be looked up (20 s).
  std::optional<Eigen::Isometry3d> lookup(const std::string& parent, const std::string& child) {
    if (!test::wait_for([&] { return tf.canTransform(parent, child, ros::Time(0)); }, 20.0)) return std::nullopt;
    return conversions::to_eigen(tf.lookupTransform(parent, child, ros::Time(0)).transform);
  }
  /// The latched message on `topic` and TF both say X (pose and covariance to 1e-9).
  void expect_published(Launch& launch, const std::string& topic, const io::ResultContext& frames,
                        const PoseWithCovariance& X);
  bool has_edge(const std::string& parent, const std::string& child) {
    for (const auto& node : static_edges) {
      for (const auto& e : node.second) {
        if (e.header.frame_id == parent && e.child_frame_id == child) return true;
      }
    }
    return false;
  }
};

/// The latched message on `topic` (20 s), or nothing.
std::optional<geometry_msgs::PoseWithCovarianceStamped> latched(const std::string& topic, double seconds = 20.0) {
  std::optional<geometry_msgs::PoseWithCovarianceStamped> msg;
  ros::NodeHandle nh;
  const ros::Subscriber sub = nh.subscribe<geometry_msgs::PoseWithCovarianceStamped>(
      topic, 1, [&](const geometry_msgs::PoseWithCovarianceStamped::ConstPtr& m) { msg = *m; });
  test::wait_for([&] { return msg.has_value(); }, seconds);
  return msg;
}

void expect_pose_near(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b, double tolerance) {
  EXPECT_LT((a.matrix() - b.matrix()).cwiseAbs().maxCoeff(), tolerance) << a.matrix() << "\n" << b.matrix();
}

void Fixture::expect_published(Launch& launch, const std::string& topic, const io::ResultContext& frames,
                               const PoseWithCovariance& X) {
  const auto msg = latched(topic);
  ASSERT_TRUE(msg) << launch.output();
  EXPECT_EQ(msg->header.frame_id, frames.parent);
  const PoseWithCovariance published = conversions::to_core(msg->pose);
  expect_pose_near(published.pose, X.pose, 1e-9);
  EXPECT_LT((published.covariance - X.covariance).cwiseAbs().maxCoeff(), 1e-9 * X.covariance.cwiseAbs().maxCoeff());
  const auto tf_X = lookup(frames.parent, frames.child);
  ASSERT_TRUE(tf_X) << launch.output();
  expect_pose_near(*tf_X, X.pose, 1e-9);
}

TEST_F(Fixture, OurResultFileGoesToTfAtTheCameraTreeRootAndToTheLatchedTopicTo1e9) {
  const PoseWithCovariance X = random_calibration(1);
  const io::ResultContext context = frames(Setup::EyeInHand, "pub_tool0", "pub_camera_optical_frame");
  const std::string file = write("ours.yaml", io::format_pose_file(X, context));
  Launch launch = publish("ours", file);

  expect_published(launch, "/ours_eye_on_hand/handeye_calibration/calibration", context, X);
  // Hung from the driver tree's root: the optical frame keeps its one parent.
  EXPECT_TRUE(test::wait_for([&] { return has_edge("pub_tool0", "pub_camera_link"); }, 5.0));
  EXPECT_TRUE(test::wait_for([&] { return !has_edge("pub_tool0", "pub_camera_optical_frame"); }, 5.0));
  EXPECT_FALSE(launch.finished()) << launch.output();
}

TEST_F(Fixture, EasyHandeyeFilesBothFormatsAndInverse) {
  const Eigen::Isometry3d X = random_calibration(2).pose;
  {  // today's format, eye-on-base: TF only (no covariance), and the log says why
    const std::string file = write("easy.yaml", test::easy_handeye_text(X, false, "easy_base", "easy_camera", true));
    Launch launch = publish("easy", file, {"eye_on_hand:=false"});
    const auto tf_X = lookup("easy_base", "easy_camera");
    ASSERT_TRUE(tf_X) << launch.output();
    expect_pose_near(*tf_X, X, 1e-9);
    EXPECT_FALSE(latched("/easy_eye_on_base/handeye_calibration/calibration", 2.0).has_value());
    EXPECT_TRUE(contains(launch.output(), "no covariance, so only TF is published")) << launch.output();
  }
  {  // the older format (parameters at the top), a frame renamed, inverse: camera -> effector
    const std::string file = write("easy_old.yaml", test::easy_handeye_text(X, true, "old_tool", "old_camera", false));
    Launch launch = publish("easy_old", file, {"robot_effector_frame:=renamed_tool", "inverse:=true"});
    const auto tf_inverse = lookup("old_camera", "renamed_tool");
    ASSERT_TRUE(tf_inverse) << launch.output();
    expect_pose_near(*tf_inverse, X.inverse(), 1e-9);
    EXPECT_TRUE(test::wait_for([&] { return has_edge("old_camera", "renamed_tool"); }, 5.0));
  }
}

TEST_F(Fixture, ABadFileStopsTheLaunchWithItsPathAndTheFix) {
  const PoseWithCovariance X = random_calibration(3);
  const io::ResultContext context = frames(Setup::EyeToHand, "bad_base", "bad_camera");
  const std::string good = io::format_pose_file(X, context);
  struct Case {
    std::string name, path;
    std::vector<std::string> extra;
    std::vector<std::string> said;  // what the output must say
  };
  const std::vector<Case> cases = {
      {"corrupt", write("corrupt.yaml", good.substr(0, good.size() / 2) + "\n  - ]: {\n"), {}, {"YAML syntax error", "corrupt.yaml:"}},
      {"missing", test::scratch_directory() + "/no_such_file.yaml", {}, {"cannot open", "no_such_file.yaml", "check the path"}},
      {"nan", write("nan.yaml", std::regex_replace(good, std::regex("translation: \\[[^\\]]*\\]"),
                                                   "translation: [.nan, 0, 0]", std::regex_constants::format_first_only)),
       {}, {"nan.yaml"}},
      {"easy_nan", write("easy_nan.yaml", "eye_on_hand: false\nrobot_base_frame: bad_base\ntracking_base_frame: bad_camera\n"
                                          "transformation: {x: .nan, y: 0, z: 0, qx: 0, qy: 0, qz: 0, qw: 1}\n"),
       {"eye_on_hand:=false"}, {"NaN or Inf in `x`", "easy_nan.yaml"}},
      {"unstated", write("unstated.yaml", good), {}, {"the calibration is eye_to_hand but it would be published in",
                                                     "give eye_on_hand:=false"}},
      {"contradicted", write("contradicted.yaml", good), {"eye_on_hand:=true"},
       {"the calibration is eye_to_hand but eye_on_hand is true", "contradicted.yaml"}},
  };
  for (const Case& c : cases) {
    Launch launch = publish(c.name, c.path, c.extra);
    // required="true": the node's exit ends the launch.
    ASSERT_TRUE(test::wait_for([&] { return launch.finished(); }, 30.0)) << c.name << ":\n" << launch.output();
    const std::string out = launch.output();
    EXPECT_TRUE(contains(out, "handeye_publisher: ")) << c.name << ":\n" << out;
    for (const std::string& s : c.said) EXPECT_TRUE(contains(out, s)) << c.name << " should say `" << s << "`:\n" << out;
    EXPECT_FALSE(has_edge("bad_base", "bad_camera")) << c.name;
  }
}

TEST_F(Fixture, TheCalibrationNodePublishesItsSavedCalibrationAtStartUp) {
  const PoseWithCovariance X = random_calibration(4);
  const io::ResultContext context = frames(Setup::EyeInHand, "start_tool0", "start_camera");
  const std::string file = write("saved.yaml", io::format_pose_file(X, context));
  Launch launch({"roslaunch", "handeye_covariance", "calibrate.launch", "namespace_prefix:=start",
                 "robot_effector_frame:=start_tool0", "tracking_base_frame:=start_camera", "calibration_file:=" + file,
                 "session_file:=" + test::scratch_directory() + "/start_session.yaml"},
                "start");
  expect_published(launch, "/start_eye_on_hand/handeye_calibration/calibration", context, X);
  // A saved calibration of other frames is not published.
  const std::string other = write("other.yaml", io::format_pose_file(X, context));
  Launch mismatch({"roslaunch", "handeye_covariance", "calibrate.launch", "namespace_prefix:=other",
                   "robot_effector_frame:=other_tool0", "tracking_base_frame:=other_camera",
                   "calibration_file:=" + other, "session_file:=" + test::scratch_directory() + "/other_session.yaml"},
                  "other");
  EXPECT_TRUE(test::wait_for([&] { return contains(mismatch.output(), "not published"); }, 30.0)) << mismatch.output();
  EXPECT_FALSE(latched("/other_eye_on_hand/handeye_calibration/calibration", 3.0).has_value());
}

}  // namespace
}  // namespace handeye

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "publish_test");
  ros::NodeHandle nh;
  // A camera driver's own tree (Debian ships no static_transform_publisher): X must be hung from its root.
  tf2_ros::StaticTransformBroadcaster camera_driver;
  camera_driver.sendTransform(handeye::conversions::to_transform_stamped(
      handeye::se3::make_pose(Eigen::Quaterniond(0.5, -0.5, 0.5, -0.5).toRotationMatrix(), Eigen::Vector3d(0.01, 0.02, 0.03)),
      "pub_camera_link", "pub_camera_optical_frame", ros::Time::now()));
  return RUN_ALL_TESTS();
}
