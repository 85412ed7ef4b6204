// Kill the node with SIGKILL and restart it with ~resume: no accepted sample is lost.
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <random>
#include <thread>

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

// Kills at random points while samples change as fast as the services allow:
// loads of 20 samples and removals, each of which rewrites the session file.
// Whatever the moment, the file must parse and hold the last confirmed state
// or the state of the request in flight; the restarted node must list it.
TEST(CalibrationNode, SessionFileSurvivesSigkillAtRandomPoints) {
  std::filesystem::remove(kSession);
  const std::string example = std::string(HANDEYE_SOURCE_DIR) + "/config/examples/eye_in_hand_samples.yaml";
  const int example_size = static_cast<int>(io::read_samples(example).samples.size());
  std::mt19937 rng(42);
  int confirmed = 0;
  std::vector<int> kill_after_ms;
  int calls_total = 0, in_flight_kept = 0;
  for (int round = 0; round < 12; ++round) {
    pid_t node = start_node(true);
    ASSERT_EQ(listed(), confirmed) << "round " << round << ": the restarted node lost or invented samples";
    const int delay_ms = std::uniform_int_distribution<int>(5, 400)(rng);
    kill_after_ms.push_back(delay_ms);
    std::thread killer([node, delay_ms] {
      std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms));
      kill(node, SIGKILL);
    });
    int pending = confirmed;
    for (int call = 0; call < 1000; ++call) {
      bool ok = false;
      if (confirmed > 8) {
        RemoveSample remove;
        remove.request.index = std::uniform_int_distribution<int>(0, confirmed - 1)(rng);
        pending = confirmed - 1;
        ok = ros::service::call("/resume/remove_sample", remove) && remove.response.success;
        if (ok) confirmed = remove.response.samples;
      } else {
        LoadSamples load;
        load.request.path = example;
        pending = example_size;
        ok = ros::service::call("/resume/load_samples", load) && load.response.success;
        if (ok) confirmed = load.response.samples;
      }
      if (!ok) break;  // the node is gone
      ++calls_total;
    }
    killer.join();
    int status = 0;
    waitpid(node, &status, 0);
    test::wait_for([] { return !ros::service::exists("/resume/list_samples", false); }, 5.0);
    // The file is whole, and holds the confirmed state or the one in flight.
    const int in_file = static_cast<int>(io::read_samples(kSession).samples.size());
    ASSERT_TRUE(in_file == confirmed || in_file == pending)
        << "round " << round << ": file has " << in_file << ", confirmed " << confirmed << ", in flight " << pending;
    in_flight_kept += (in_file == pending && pending != confirmed) ? 1 : 0;
    confirmed = in_file;
  }
  std::printf("12 SIGKILLs after %d..%d ms (%d confirmed changes in all): the session file always parsed and held "
              "the confirmed state, or (%d times) the request in flight\n",
              *std::min_element(kill_after_ms.begin(), kill_after_ms.end()),
              *std::max_element(kill_after_ms.begin(), kill_after_ms.end()), calls_total, in_flight_kept);
  pid_t node = start_node(true);
  EXPECT_EQ(listed(), confirmed);
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
