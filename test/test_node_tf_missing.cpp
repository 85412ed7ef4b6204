#include <filesystem>
#include <fstream>

#include "handeye_covariance/simulation/simulation.h"
#include "handeye_covariance/io/yaml_io.h"
#include "node_test_helpers.h"
#include "test_helpers.h"

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

// The services' part of the bad-input table (the CLI's is test_bad_inputs.cpp).
// With no robot TF the node takes no samples by itself, so every count below is
// the services' doing. A refused request must answer success: false with the
// named error and its fix, and leave the samples, the session file and the
// calibration file as they were.

std::string write_file(const std::string& name, const std::string& text) {
  // Its own directory made here: on a fresh machine no other rostest need have run first.
  std::filesystem::create_directories("/tmp/handeye_covariance_rostest");
  const std::string path = "/tmp/handeye_covariance_rostest/bad_" + name;
  std::ofstream file(path);
  file << text;
  EXPECT_TRUE(file.good()) << "cannot write " << path;
  return path;
}

SampleSet session(int n, Setup setup = Setup::EyeInHand) {
  Rng rng(17);
  SampleSet set = simulate_session(rng, setup, typical_X(setup), n, test::sim_noise()).samples;
  if (setup == Setup::EyeInHand) set.rig.frames = FrameNames{};  // the node's default frame names
  return set;
}

std::string samples_text_with_first_effector(const std::string& pose) {
  std::string text = io::format_samples(session(12));
  const std::size_t begin = text.find("{", text.find("effector:", text.find("samples:")));
  return text.replace(begin, text.find("}", begin) + 1 - begin, pose);
}

int listed_samples() {
  ListSamples list;
  EXPECT_TRUE(test::call(kNs + "list_samples", list));
  return list.response.samples;
}

TEST(CalibrationNode, BadServiceRequestsAreRefusedWithAReasonAndLoseNothing) {
  const std::string session_file = "/tmp/handeye_covariance_rostest/notf_session.yaml";
  const std::string calibration_file = "/tmp/handeye_covariance_rostest/notf.yaml";
  LoadSamples good;
  good.request.path = write_file("good.yaml", io::format_samples(session(12)));
  ASSERT_TRUE(test::call(kNs + "load_samples", good));
  ASSERT_TRUE(good.response.success) << good.response.message;
  Calibrate first;
  ASSERT_TRUE(test::call(kNs + "calibrate", first));
  ASSERT_TRUE(first.response.success) << first.response.message;
  const std::string session_before = io::read_file(session_file), calibration_before = io::read_file(calibration_file);
  ASSERT_EQ(listed_samples(), 12);

  struct Row {
    std::string id, path, error, mentions;
  };
  SampleSet parallel = session(6);
  for (PoseSample& s : parallel.samples) s.T_base_effector.linear() = parallel.samples[0].T_base_effector.linear();
  const std::vector<Row> loads = {
      {"missing file", "/nonexistent/samples.yaml", "IoError", "/nonexistent/samples.yaml"},
      {"malformed YAML", write_file("malformed.yaml", "setup: eye_in_hand\nsamples: [\n"), "MalformedFile", "bad_malformed.yaml:"},
      {"missing key", write_file("missing.yaml", samples_text_with_first_effector("{translation: [0.1, 0.2, 0.3]}")),
       "MissingKey", "samples[0].effector"},
      {"wrong length", write_file("length.yaml", samples_text_with_first_effector("{translation: [0.1], rotation: [0, 0, 0, 1]}")),
       "WrongLength", "samples[0].effector.translation"},
      {"NaN", write_file("nan.yaml", samples_text_with_first_effector("{translation: [.nan, 0, 0], rotation: [0, 0, 0, 1]}")),
       "NonFinite", "samples[0].effector.translation[0]"},
      {"quaternion", write_file("quat.yaml", samples_text_with_first_effector("{translation: [0, 0, 0], rotation: [0, 0, 0, 2]}")),
       "QuaternionNotUnit", "samples[0].effector.rotation"},
      {"matrix", write_file("matrix.yaml", samples_text_with_first_effector("{matrix: [2, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]}")),
       "RotationNotOrthonormal", "samples[0].effector.matrix"},
      {"other setup", write_file("to_hand.yaml", io::format_samples(session(12, Setup::EyeToHand))), "MalformedFile", "eye_to_hand"},
  };
  for (const Row& row : loads) {
    SCOPED_TRACE(row.id);
    LoadSamples load;
    load.request.path = row.path;
    ASSERT_TRUE(test::call(kNs + "load_samples", load));
    EXPECT_FALSE(load.response.success);
    EXPECT_NE(load.response.message.find(row.error), std::string::npos) << load.response.message;
    EXPECT_NE(load.response.message.find(row.mentions), std::string::npos) << load.response.message;
    EXPECT_NE(load.response.message.find("Fix:"), std::string::npos) << load.response.message;
    EXPECT_EQ(listed_samples(), 12);
    EXPECT_EQ(io::read_file(session_file), session_before);
  }

  SaveSamples save;
  save.request.path = session_file + "/not_a_directory/samples.yaml";
  ASSERT_TRUE(test::call(kNs + "save_samples", save));
  EXPECT_FALSE(save.response.success);
  EXPECT_NE(save.response.message.find("IoError"), std::string::npos) << save.response.message;

  RemoveSample remove;
  remove.request.index = 12;
  ASSERT_TRUE(test::call(kNs + "remove_sample", remove));
  EXPECT_FALSE(remove.response.success);
  EXPECT_NE(remove.response.message.find("0..11"), std::string::npos) << remove.response.message;
  EXPECT_EQ(listed_samples(), 12);

  // A valid but degenerate session loads; /calibrate then refuses it and keeps the last calibration.
  LoadSamples degenerate;
  degenerate.request.path = write_file("translation.yaml", io::format_samples(parallel));
  ASSERT_TRUE(test::call(kNs + "load_samples", degenerate));
  ASSERT_TRUE(degenerate.response.success) << degenerate.response.message;
  Calibrate refused;
  ASSERT_TRUE(test::call(kNs + "calibrate", refused));
  EXPECT_FALSE(refused.response.success);
  EXPECT_NE(refused.response.message.find("PureTranslation"), std::string::npos) << refused.response.message;
  EXPECT_NE(refused.response.message.find("Fix:"), std::string::npos) << refused.response.message;
  EXPECT_EQ(io::read_file(calibration_file), calibration_before);
}

}  // namespace
}  // namespace handeye

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_tf_missing");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
