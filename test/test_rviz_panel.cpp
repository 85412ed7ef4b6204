// The calibration panel in a real rviz (rviz::VisualizationFrame, the class the
// rviz program runs, with the package's config: the panel is loaded by pluginlib
// from plugin_description.xml) against the simulated rig, with auto-sampling off.
// The test drives the panel as an operator would, through Qt's test tools: it
// presses "Take sample" until the node holds 5 samples, then "Calibrate",
// "Suggest pose", "Remove selected", "Reset" (answering its question) and, with a
// session holding a wrong detection, "Calibrate" again (the row marked rejected), and
// checks what the panel shows against the node's ~status. Screenshots of the
// screen (Xvfb) after start-up, after 5 samples and after /calibrate are kept as
// test artifacts (docs/ holds a copy).
#include <QAbstractButton>
#include <QApplication>
#include <QLabel>
#include <QMessageBox>
#include <QPushButton>
#include <QTableWidget>
#include <QTest>
#include <QTimer>

#include <rviz/visualization_frame.h>
#include <std_msgs/Float64.h>
#include <visualization_msgs/MarkerArray.h>

#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "arm_watch.h"
#include "handeye_covariance/core/errors.h"
#include "node_test_helpers.h"

namespace handeye {
namespace {

std::string artifact_dir, config_path, samples_path, test_case;
const std::string kNs = "/handeye_eye_on_hand/";
QApplication* app = nullptr;

/// Runs rviz (its Qt events; rviz spins ROS in its update) until `done()` or `seconds` pass.
bool pump_until(const std::function<bool()>& done, double seconds) {
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(seconds);
  while (ros::ok() && !done() && ros::WallTime::now() < deadline) {
    app->processEvents(QEventLoop::AllEvents, 20);
    ros::spinOnce();
    ros::WallDuration(0.01).sleep();
  }
  return done();
}

void screenshot(const std::string& name) {
  std::filesystem::create_directories(artifact_dir);
  pump_until([] { return false; }, 1.0);  // let rviz draw the latest state
  const std::string png = artifact_dir + "/" + name;
  const std::string capture = "import -window root " + png + " 2>/dev/null";
  EXPECT_EQ(std::system(capture.c_str()), 0) << capture;
  std::printf("[rviz panel] screenshot %s\n", png.c_str());
}

/// Presses `button` once it is enabled (the panel disables its buttons while a call is out).
void press(QPushButton* button) {
  ASSERT_TRUE(pump_until([&] { return button->isEnabled(); }, 15.0))
      << button->objectName().toStdString() << " stayed disabled: a call never returned";
  QTest::mouseClick(button, Qt::LeftButton);
}

/// rviz with the package's config, and the calibration panel in it.
void open_rviz(std::unique_ptr<rviz::VisualizationFrame>& frame, QWidget*& panel) {
  frame = std::make_unique<rviz::VisualizationFrame>();
  frame->setApp(app);
  frame->setSplashPath("");
  frame->initialize(QString::fromStdString(config_path));
  frame->show();
  ASSERT_TRUE(pump_until(
      [&] {
        for (QWidget* w : frame->findChildren<QWidget*>()) {
          if (std::string(w->metaObject()->className()) == "handeye::rviz_plugin::CalibrationPanel") panel = w;
        }
        return panel != nullptr;
      },
      30.0))
      << "the panel did not load from " << config_path << " (pluginlib: plugin_description.xml?)";
}

/// The same formatting as the panel: mm to 2 decimals, degrees to 3.
QString mm(double value) { return QString::number(value, 'f', 2); }
QString deg(double value) { return QString::number(value, 'f', 3); }

TEST(RvizPanel, DrivesTheCalibrationNodeAndShowsWhatItsStatusSays) {
  if (!test_case.empty()) GTEST_SKIP() << "the " << test_case << " case (rviz_panel_" << test_case << ".test)";
  ASSERT_NE(std::getenv("DISPLAY"), nullptr) << "no X display: run under ./scripts/test (it starts Xvfb)";
  test::StatusWatcher status(kNs + "handeye_calibration/status");
  visualization_msgs::MarkerArray next_pose;
  ros::NodeHandle nh;
  auto next_pose_sub = nh.subscribe<visualization_msgs::MarkerArray>(
      kNs + "handeye_calibration/next_pose_markers", 1, [&](const auto& msg) { next_pose = *msg; });

  const test::DisplayLock display;  // the X display is this test's while it runs (see the lock)
  std::unique_ptr<rviz::VisualizationFrame> frame;
  QWidget* panel = nullptr;
  ASSERT_NO_FATAL_FAILURE(open_rviz(frame, panel));
  const auto find = [&](const char* name) {
    QWidget* w = panel->findChild<QWidget*>(name);
    EXPECT_NE(w, nullptr) << "no widget `" << name << "` in the panel";
    return w;
  };
  auto* take = qobject_cast<QPushButton*>(find("take_sample"));
  auto* calibrate = qobject_cast<QPushButton*>(find("calibrate"));
  auto* suggest = qobject_cast<QPushButton*>(find("suggest_pose"));
  auto* remove = qobject_cast<QPushButton*>(find("remove_sample"));
  auto* reset = qobject_cast<QPushButton*>(find("reset"));
  auto* table = qobject_cast<QTableWidget*>(find("samples"));
  auto* samples_label = qobject_cast<QLabel*>(find("samples_label"));
  auto* sigma_label = qobject_cast<QLabel*>(find("sigma_label"));
  auto* object_label = qobject_cast<QLabel*>(find("object_label"));
  auto* target_label = qobject_cast<QLabel*>(find("target_label"));
  auto* reply_label = qobject_cast<QLabel*>(find("reply_label"));
  ASSERT_TRUE(take && calibrate && suggest && remove && reset && table && samples_label && sigma_label &&
              object_label && target_label && reply_label);

  // Start-up: the panel follows the node of the config's namespace, which has no samples.
  ASSERT_TRUE(pump_until([&] { return status.received && samples_label->text().contains("<b>0 samples</b>"); }, 60.0))
      << "panel: " << samples_label->text().toStdString();
  EXPECT_EQ(status.latest.samples, 0);
  EXPECT_EQ(table->rowCount(), 0);
  screenshot("rviz_panel_startup.png");

  // "Take sample", pressed through Qt: the node samples only then (auto_sample is off),
  // and only while the rig stands still at a pose, so the operator presses again.
  // A press waits for the reply, and a taken sample for ~status to count it (the reply
  // and ~status come on different connections), so no press is one too many.
  int presses = 0;
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(90.0);
  while (status.latest.samples < 5 && ros::WallTime::now() < deadline) {
    ASSERT_TRUE(pump_until([&] { return take->isEnabled(); }, 10.0)) << "a call never returned";
    QTest::mouseClick(take, Qt::LeftButton);
    ++presses;
    ASSERT_TRUE(pump_until([&] { return take->isEnabled(); }, 10.0)) << "take_sample never replied";
    const QString reply = reply_label->text();
    if (reply.startsWith("Sample taken: ")) {
      const int taken = reply.section(' ', 2, 2).toInt();
      ASSERT_TRUE(pump_until([&] { return status.latest.samples >= taken; }, 5.0)) << reply.toStdString();
    } else {
      pump_until([] { return false; }, 0.3);  // refused: the rig is moving
    }
  }
  ASSERT_EQ(status.latest.samples, 5) << presses << " presses; panel: " << reply_label->text().toStdString();
  std::printf("[rviz panel] 5 samples after %d presses of Take sample\n", presses);
  // The table: a row per sample, each with its residual once the estimate is of these 5.
  ASSERT_TRUE(pump_until(
      [&] {
        return table->rowCount() == 5 && status.latest.sample_residual_mm.size() == 5 && table->item(4, 1) &&
               table->item(4, 1)->text() == mm(status.latest.sample_residual_mm[4]);
      },
      20.0))
      << table->rowCount() << " rows, " << status.latest.sample_residual_mm.size() << " residuals on ~status";
  for (int i = 0; i < 5; ++i) {
    EXPECT_EQ(table->item(i, 1)->text(), mm(status.latest.sample_residual_mm[i]));
    EXPECT_EQ(table->item(i, 2)->text(), deg(status.latest.sample_residual_deg[i]));
    EXPECT_GT(status.latest.sample_residual_sigma[i], 0.0);
    EXPECT_LT(status.latest.sample_residual_sigma[i], 6.0) << "sample " << i << " of a clean simulated session";
    EXPECT_TRUE(table->item(i, 4)->text().startsWith("kept")) << table->item(i, 4)->text().toStdString();
  }
  EXPECT_TRUE(samples_label->text().contains("<b>5 samples</b>")) << samples_label->text().toStdString();
  screenshot("rviz_panel_5_samples.png");

  // "Calibrate": the reply, then the figures against ~status.
  press(calibrate);
  ASSERT_TRUE(pump_until([&] { return reply_label->text().startsWith("Calibrated"); }, 30.0))
      << reply_label->text().toStdString();
  EXPECT_TRUE(reply_label->text().contains("from 5 samples")) << reply_label->text().toStdString();
  ASSERT_TRUE(status.latest.has_estimate);
  const CalibrationStatus& s = status.latest;
  for (int i = 0; i < 3; ++i) {
    EXPECT_TRUE(sigma_label->text().contains(mm(s.sigma_translation_mm[i]))) << sigma_label->text().toStdString();
    EXPECT_TRUE(sigma_label->text().contains(deg(s.sigma_rotation_deg[i]))) << sigma_label->text().toStdString();
  }
  EXPECT_TRUE(object_label->text().contains(mm(s.object_error_mm) + " mm")) << object_label->text().toStdString();
  EXPECT_TRUE(object_label->text().contains("target " + mm(s.target_tolerance_mm))) << object_label->text().toStdString();
  EXPECT_EQ(target_label->text().contains("Target reached"), static_cast<bool>(s.target_reached))
      << target_label->text().toStdString() << " while ~status says target_reached " << int(s.target_reached);
  std::printf("[rviz panel] after Calibrate: %s | %s | %s\n", sigma_label->text().toStdString().c_str(),
              object_label->text().toStdString().c_str(), target_label->text().toStdString().c_str());
  // The suggested next pose in 3D: a ghost effector frame, the frustum and a label.
  ASSERT_TRUE(pump_until([&] { return next_pose.markers.size() == 4; }, 10.0)) << next_pose.markers.size() << " markers";
  EXPECT_EQ(next_pose.markers[0].action, visualization_msgs::Marker::DELETEALL);
  EXPECT_EQ(next_pose.markers[1].header.frame_id, "base_link");
  EXPECT_EQ(next_pose.markers[2].points.size(), 16u) << "the frustum: 4 edges from the camera and the 4 sides";
  screenshot("rviz_panel_calibrated.png");

  press(suggest);
  ASSERT_TRUE(pump_until([&] { return reply_label->text().startsWith("Best next pose"); }, 30.0))
      << reply_label->text().toStdString();

  // "Remove selected": the row chosen in the table.
  press(remove);
  EXPECT_TRUE(reply_label->text().contains("Select a sample")) << "nothing selected: " << reply_label->text().toStdString();
  table->selectRow(2);
  press(remove);
  ASSERT_TRUE(pump_until(
      [&] {
        return status.latest.samples == 4 && table->rowCount() == 4 && reply_label->text().contains("Removed sample 2");
      },
      20.0))
      << status.latest.samples << " samples, " << table->rowCount() << " rows; " << reply_label->text().toStdString();

  // "Reset" asks first: "No" keeps the samples, "Yes" drops them.
  const auto answer = [](QMessageBox::StandardButton which) {
    QTimer::singleShot(300, [which] {
      auto* box = qobject_cast<QMessageBox*>(QApplication::activeModalWidget());
      if (box) QTest::mouseClick(box->button(which), Qt::LeftButton);
    });
  };
  answer(QMessageBox::No);
  press(reset);
  pump_until([] { return false; }, 1.5);
  EXPECT_EQ(status.latest.samples, 4);
  answer(QMessageBox::Yes);
  press(reset);
  ASSERT_TRUE(pump_until([&] { return status.latest.samples == 0 && table->rowCount() == 0; }, 20.0))
      << status.latest.samples << " samples";
  EXPECT_TRUE(sigma_label->text().contains("no estimate")) << sigma_label->text().toStdString();
  ASSERT_TRUE(pump_until([&] { return next_pose.markers.size() == 1; }, 10.0)) << "the ghost stayed after Reset";

  // A rejected sample in the table: the example session with sample 3 paired with sample 0's
  // pattern pose (a detection with the wrong stamp), loaded into the node, then "Calibrate".
  const int loaded = test::load_with_wrong_detection(kNs, samples_path);
  ASSERT_GT(loaded, 3);
  press(calibrate);
  ASSERT_TRUE(pump_until(
      [&] {
        return reply_label->text().contains("1 sample(s) rejected") && table->rowCount() == loaded &&
               table->item(3, 4) && table->item(3, 4)->text().startsWith("rejected:");
      },
      30.0))
      << reply_label->text().toStdString() << "; row 3: " << (table->item(3, 4) ? table->item(3, 4)->text().toStdString() : "none");
  EXPECT_EQ(status.latest.rejected_samples, std::vector<int>{3});
  ASSERT_EQ(status.latest.rejected_reasons.size(), 1u);
  EXPECT_EQ(table->item(3, 4)->text(), "rejected: " + QString::fromStdString(status.latest.rejected_reasons[0]))
      << "the reason, as the node gives it";
  ASSERT_GT(status.latest.sample_residual_sigma.size(), 3u);
  EXPECT_GT(status.latest.sample_residual_sigma[3], 5.0) << "the rejected sample, judged against the rest";
  EXPECT_TRUE(table->item(2, 4)->text().startsWith("kept"));
  screenshot("rviz_panel_rejected.png");

  frame.reset();  // before QApplication and ROS go
}

// Move / Auto / Stop against the simulated arm (test/rviz_panel_motion.test): the
// panel moves the arm to one view, starts calibrating by itself, stops it during a
// move, and starts again until the target; the motion line follows ~motion_status.
TEST(RvizPanel, MovesTheArmStopsItAndCalibratesByItself) {
  if (test_case != "motion") GTEST_SKIP() << "needs the simulated arm (rviz_panel_motion.test)";
  ASSERT_NE(std::getenv("DISPLAY"), nullptr) << "no X display: run under ./scripts/test (it starts Xvfb)";
  test::StatusWatcher status(kNs + "handeye_calibration/status");
  const test::ArmWatch arm;
  const test::DisplayLock display;
  std::unique_ptr<rviz::VisualizationFrame> frame;
  QWidget* panel = nullptr;
  ASSERT_NO_FATAL_FAILURE(open_rviz(frame, panel));
  auto* move = panel->findChild<QPushButton*>("move");
  auto* automatic = panel->findChild<QPushButton*>("auto_calibrate");
  auto* stop = panel->findChild<QPushButton*>("stop_motion");
  auto* motion = panel->findChild<QLabel*>("motion_label");
  ASSERT_TRUE(move && automatic && stop && motion);
  ASSERT_TRUE(pump_until([&] { return status.received && status.latest.samples >= 1; }, 60.0)) << "no first sample";

  // Confirm mode: the first move is planned and shown before anything moves; Move moves
  // there and samples, and the next one is planned and shown again.
  ASSERT_TRUE(pump_until([&] { return motion->text().contains("planned:"); }, 30.0)) << motion->text().toStdString();
  press(move);
  ASSERT_TRUE(pump_until([&] { return status.latest.samples >= 2 || motion->text().contains("failed:"); }, 60.0))
      << motion->text().toStdString();
  ASSERT_GE(status.latest.samples, 2) << motion->text().toStdString();
  ASSERT_TRUE(pump_until([&] { return motion->text().contains("planned:"); }, 30.0)) << motion->text().toStdString();
  // Auto, then Stop half way through a move (at speed): stopped, and the arm holds where it was.
  press(automatic);
  ASSERT_TRUE(pump_until([&] { return motion->text().contains("moving:"); }, 30.0)) << motion->text().toStdString();
  const double duration = std::stod(motion->text().toStdString().substr(motion->text().indexOf("moving:") + 8));
  pump_until([] { return false; }, 0.5 * duration);
  EXPECT_TRUE(stop->isEnabled()) << "Stop is never disabled";
  const double pressed = ros::Time::now().toSec();
  QTest::mouseClick(stop, Qt::LeftButton);
  ASSERT_TRUE(pump_until([&] { return motion->text().contains("stopped:"); }, 2.0)) << motion->text().toStdString();
  pump_until([&] { return arm.still_for(0.5); }, 5.0);
  const std::optional<double> travel = arm.travel_after(pressed, 0.0);
  ASSERT_TRUE(travel) << "the arm did not come to rest";
  const std::optional<Eigen::VectorXd> before = arm.at(pressed - 0.05), then = arm.at(pressed);
  const double speed = before && then ? (*then - *before).cwiseAbs().maxCoeff() / 0.05 : 0.0;
  std::printf("[rviz panel] Stop half way through a %.2f s move, the fastest joint at %.1f deg/s: joint travel after it "
              "%.3f deg\n", duration, degrees(speed), degrees(*travel));
  EXPECT_LE(degrees(*travel), 0.5);
  EXPECT_GT(degrees(speed), 5.0) << "Stop came while the arm moved";
  // Nothing is commanded after Stop (the sampler may take a sample where the arm stands).
  const std::size_t commands_after_stop = arm.commands();
  pump_until([] { return false; }, 3.0);
  EXPECT_TRUE(motion->text().contains("stopped:")) << "nothing moves after Stop: " << motion->text().toStdString();
  EXPECT_EQ(arm.commands(), commands_after_stop);
  EXPECT_TRUE(arm.still_for(2.5));
  // Auto again, to the target.
  press(automatic);
  ASSERT_TRUE(pump_until([&] { return motion->text().contains("done:") || motion->text().contains("failed:"); }, 150.0))
      << motion->text().toStdString();
  EXPECT_TRUE(motion->text().contains("done:")) << motion->text().toStdString();
  ASSERT_TRUE(pump_until([&] { return status.latest.target_reached; }, 10.0));
  std::printf("[rviz panel] %s (%d samples)\n", motion->text().toStdString().c_str(), status.latest.samples);
  const std::vector<std::string> not_whole = arm.not_taken_whole();
  EXPECT_TRUE(not_whole.empty()) << "a command the controller did not take as sent: " << not_whole.front();
  screenshot("rviz_panel_motion.png");
  frame.reset();
}

// Check against the simulated rig (test/rviz_panel_check.test): Calibrate, then the rig's
// camera moves 3 mm on its mount and Check takes 5 new views: the panel shows the verdict
// (X changed, in red) and the views' table, each view's error against its predicted 1 sigma.
TEST(RvizPanel, ChecksTheCalibrationAndShowsABumpedCamera) {
  if (test_case != "check") GTEST_SKIP() << "needs rviz_panel_check.test";
  ASSERT_NE(std::getenv("DISPLAY"), nullptr) << "no X display: run under ./scripts/test (it starts Xvfb)";
  test::StatusWatcher status(kNs + "handeye_calibration/status");
  ros::NodeHandle nh;
  ros::Publisher bump = nh.advertise<std_msgs::Float64>("/rig_simulator/bump_camera_mm", 1, true);
  const test::DisplayLock display;
  std::unique_ptr<rviz::VisualizationFrame> frame;
  QWidget* panel = nullptr;
  ASSERT_NO_FATAL_FAILURE(open_rviz(frame, panel));
  auto* calibrate = panel->findChild<QPushButton*>("calibrate");
  auto* check = panel->findChild<QPushButton*>("check_calibration");
  auto* verdict = panel->findChild<QLabel*>("check_label");
  auto* views = panel->findChild<QTableWidget*>("check_views");
  auto* reply = panel->findChild<QLabel*>("reply_label");
  ASSERT_TRUE(calibrate && check && verdict && views && reply);
  EXPECT_FALSE(views->isVisible());  // no check yet

  ASSERT_TRUE(pump_until([&] { return status.received && status.latest.samples >= 10; }, 90.0))
      << status.latest.samples << " samples";
  press(calibrate);
  ASSERT_TRUE(pump_until([&] { return reply->text().contains("Calibrated"); }, 60.0)) << reply->text().toStdString();
  const int samples = status.latest.samples;

  std_msgs::Float64 mm;
  mm.data = 3.0;
  bump.publish(mm);
  pump_until([] { return false; }, 0.5);
  press(check);
  ASSERT_TRUE(pump_until([&] { return verdict->text().contains("collecting"); }, 10.0)) << verdict->text().toStdString();
  ASSERT_TRUE(pump_until([&] { return verdict->text().contains("changed") || verdict->text().contains("consistent"); },
                         60.0))
      << verdict->text().toStdString();
  EXPECT_TRUE(verdict->text().contains("X changed")) << verdict->text().toStdString();
  EXPECT_TRUE(verdict->text().contains("#e05050")) << "a change is shown in red";
  ASSERT_TRUE(views->isVisible());
  ASSERT_EQ(views->rowCount(), 5);
  for (int i = 0; i < 5; ++i) EXPECT_GT(views->item(i, 2)->text().toDouble(), 0.0) << "a predicted 1 sigma per view";
  EXPECT_LE(status.latest.samples, samples + 1) << "the check's views are not the calibration's samples";
  std::printf("[rviz panel] %s\n", verdict->text().toStdString().c_str());
  screenshot("rviz_panel_check.png");
  frame.reset();
}

}  // namespace
}  // namespace handeye

namespace {

int run_tests(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_rviz_panel");
  QApplication app(argc, argv);
  handeye::app = &app;
  ros::NodeHandle nh, pn("~");
  handeye::artifact_dir = pn.param<std::string>("artifact_dir", "/tmp");
  handeye::config_path = pn.param<std::string>("config", "");
  handeye::samples_path = pn.param<std::string>("samples", "");
  handeye::test_case = pn.param<std::string>("case", "");
  return RUN_ALL_TESTS();
}

}  // namespace

// Debian's rviz (1.14.19) sometimes dies at start-up on a loaded machine, before the panel
// does anything: a segfault in its own Grid display's first status (rviz::Display::
// setStatusInternal -> PropertyTreeModel::beginInsert -> QAbstractItemModel::
// rowsAboutToBeInserted): 1 run of 13 here beside two busy cores (the core's backtrace,
// 2026-11-28); it failed rviz_panel_motion in 2 of the last 3 clean runs of the suite.
// So the tests run in a child process, and run once more if that child is killed by a
// signal within its first 20 seconds. A later crash, a second one, or any failed
// assertion stands.
int main(int argc, char** argv) {
  for (int attempt = 0;; ++attempt) {
    const auto start = std::chrono::steady_clock::now();
    const pid_t child = ::fork();
    if (child < 0) return run_tests(argc, argv);
    if (child == 0) {
      ::prctl(PR_SET_PDEATHSIG, SIGKILL);  // roslaunch stops the parent: the child goes with it
      return run_tests(argc, argv);
    }
    int status = 0;
    while (::waitpid(child, &status, 0) < 0 && errno == EINTR) {
    }
    if (WIFEXITED(status)) return WEXITSTATUS(status);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const int signal = WIFSIGNALED(status) ? WTERMSIG(status) : 0;
    if (attempt == 0 && seconds < 20.0) {
      std::fprintf(stderr, "test_rviz_panel: killed by signal %d %.1f s after it started (rviz's start-up): once more\n",
                   signal, seconds);
      continue;
    }
    std::fprintf(stderr, "test_rviz_panel: killed by signal %d %.1f s after it started\n", signal, seconds);
    return 128 + signal;
  }
}
