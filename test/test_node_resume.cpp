// Kill the node with SIGKILL and restart it with ~resume: no accepted sample is lost.
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>

#include <filesystem>

#include "handeye_covariance/io/yaml_io.h"
#include "node_test_helpers.h"

extern char** environ;

namespace handeye {
namespace {

const std::string kSession = "/tmp/handeye_covariance_rostest/resume_session.yaml";

pid_t start_node(bool resume) {
  std::vector<std::string> args = {CALIBRATION_NODE,
                                   "__name:=handeye_calibration",
                                   "__ns:=/resume",
                                   "_detection_input:=pose",
                                   "_session_file:=" + kSession,
                                   "_calibration_file:=/tmp/handeye_covariance_rostest/resume.yaml",
                                   std::string("_resume:=") + (resume ? "true" : "false")};
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  EXPECT_EQ(posix_spawn(&pid, CALIBRATION_NODE, nullptr, nullptr, argv.data(), environ), 0);
  return pid;
}

void kill_hard(pid_t pid) {
  kill(pid, SIGKILL);
  int status = 0;
  waitpid(pid, &status, 0);
  // Wait until the master forgets the dead node's services.
  test::wait_for([] { return !ros::service::exists("/resume/list_samples", false); }, 5.0);
}

int listed() {
  ListSamples list;
  return test::call("/resume/list_samples", list) ? list.response.samples : -1;
}

TEST(CalibrationNode, ResumesEverySampleAfterSigkill) {
  std::filesystem::remove(kSession);
  pid_t node = start_node(false);
  LoadSamples load;
  load.request.path = std::string(HANDEYE_SOURCE_DIR) + "/config/examples/eye_in_hand_samples.yaml";
  ASSERT_TRUE(test::call("/resume/load_samples", load));
  ASSERT_TRUE(load.response.success) << load.response.message;
  RemoveSample remove;
  remove.request.index = 4;
  ASSERT_TRUE(test::call("/resume/remove_sample", remove));
  ASSERT_EQ(remove.response.samples, 19);
  kill_hard(node);

  // The session file is complete and parses.
  EXPECT_EQ(io::read_samples(kSession).samples.size(), 19u);

  node = start_node(true);
  EXPECT_EQ(listed(), 19);
  Calibrate calibrate;
  ASSERT_TRUE(test::call("/resume/calibrate", calibrate));
  EXPECT_TRUE(calibrate.response.success) << calibrate.response.message;
  kill_hard(node);

  // Without ~resume the node starts empty (and says so in its session file only once a sample arrives).
  node = start_node(false);
  EXPECT_EQ(listed(), 0);
  kill_hard(node);
}

}  // namespace
}  // namespace handeye

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_resume");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
