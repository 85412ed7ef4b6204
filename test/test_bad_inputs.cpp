// The bad-input table (docs/troubleshooting.md, "What can go wrong"): every class of bad input a
// new user produces, through the real `handeye` binary (solve, bag, compose,
// noise, suggest). Each refusal must exit 2, name the error, say where, say what
// to do ("Fix:"), and leave the output path as it was: no partial file, and an
// existing file untouched. Inputs that are only partly bad (a looping bag, a gap
// in TF) must give the same X as the clean input, with the problem reported.
// The services' table is in test_node_tf_missing.cpp (tf_missing.test).
#include <gtest/gtest.h>

#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <tf2_msgs/TFMessage.h>

#include <fstream>
#include <functional>
#include <regex>
#include <set>

#include "cli_helpers.h"
#include "handeye_covariance/simulation/simulation.h"
#include "handeye_covariance/io/yaml_io.h"
#include "handeye_covariance/ros/bag.h"
#include "handeye_covariance/ros/messages.h"
#include "test_helpers.h"

namespace handeye {
namespace {

using Eigen::Isometry3d;
using Eigen::Vector3d;
using test::CliRun;
using test::run;
using test::temp;

constexpr double kDeg = M_PI / 180.0;
const char* kOldContent = "an earlier result that a failed run must not touch\n";

// ------------------------------------------------------------------ inputs

SampleSet simulated(int n, std::uint64_t seed = 11) {
  Rng rng(seed);
  return simulate_session(rng, Setup::EyeInHand, typical_X(Setup::EyeInHand), n, test::sim_noise()).samples;
}

/// Samples whose robot rotations all turn about one axis (z), the pattern
/// poses consistent with a true X: ParallelRotationAxes.
SampleSet about_one_axis() {
  Rng rng(5);
  SampleSet set = simulated(3);
  set.samples.clear();
  const Isometry3d X = typical_X(Setup::EyeInHand);
  const Isometry3d T_base_pattern = se3::make_pose(Eigen::Matrix3d::Identity(), Vector3d(0.6, 0, 0));
  for (int i = 0; i < 8; ++i) {
    PoseSample s;
    s.T_base_effector = se3::make_pose(so3::exp(Vector3d(0, 0, 0.3 * i - 1.0)),
                                       Vector3d(0.3 + 0.02 * i, 0.05 * (i % 3), 0.5 - 0.01 * i));
    s.T_camera_pattern = X.inverse() * s.T_base_effector.inverse() * T_base_pattern;
    set.samples.push_back(s);
  }
  return set;
}

std::string write(const std::string& name, const std::string& text) {
  const std::string path = temp(name);
  std::ofstream(path) << text;
  return path;
}

std::string write(const std::string& name, const SampleSet& set) { return write(name, io::format_samples(set)); }

/// The shipped-format samples file with `from` replaced by `to` (its first occurrence).
std::string edited(const std::string& name, const std::string& from, const std::string& to) {
  std::string text = io::format_samples(simulated(12));
  const std::size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return write(name, text.replace(at, from.size(), to));
}

/// The same file with the first sample's effector pose written as `pose`.
std::string with_effector(const std::string& name, const std::string& pose) {
  std::string text = io::format_samples(simulated(12));
  const std::size_t begin = text.find("{", text.find("effector:", text.find("samples:")));
  return write(name, text.replace(begin, text.find("}", begin) + 1 - begin, pose));
}

/// 12 good samples and `bad` whose pattern is flipped about its x axis (a wrong detection).
SampleSet with_flipped(int bad) {
  SampleSet set = simulated(12 + bad, 23);
  for (int i = 0; i < bad; ++i) {
    PoseSample& s = set.samples[static_cast<std::size_t>(3 * i + 1)];
    s.T_camera_pattern = s.T_camera_pattern * se3::make_pose(so3::exp(Vector3d(M_PI, 0, 0)), Vector3d::Zero());
  }
  return set;
}

// ------------------------------------------------------------------ bags

const std::string& clean_bag() {
  static const std::string path = [] {
    const std::string p = ::testing::TempDir() + "/bad_inputs_clean.bag";
    BagSimulationOptions options;
    options.poses = 8;
    options.seed = 4;
    options.wrong_detections = 0.0;
    write_simulated_bag(p, options);
    return p;
  }();
  return path;
}

/// Copies the clean bag through `edit`, which writes each message (as it likes) to the new bag.
using BagEdit = std::function<void(rosbag::Bag& out, const rosbag::MessageInstance& m)>;
std::string rewritten_bag(const std::string& name, const BagEdit& edit, int passes = 1) {
  const std::string path = temp(name);
  rosbag::Bag in(clean_bag(), rosbag::bagmode::Read), out(path, rosbag::bagmode::Write);
  for (int pass = 0; pass < passes; ++pass) {
    for (const rosbag::MessageInstance& m : rosbag::View(in)) {
      if (pass == 0) {
        edit(out, m);
        continue;
      }
      // A later pass of a looping recording: the bag's clock goes on, the header stamps start over.
      const ros::Duration shift = (rosbag::View(in).getEndTime() - rosbag::View(in).getBeginTime()) * pass + ros::Duration(1.0);
      out.write(m.getTopic(), m.getTime() + shift, m, m.getConnectionHeader());
    }
  }
  return path;
}

void copy(rosbag::Bag& out, const rosbag::MessageInstance& m) { out.write(m.getTopic(), m.getTime(), m, m.getConnectionHeader()); }

/// Edits each detection message, copies the rest.
std::string with_detections(const std::string& name, const std::function<void(TagDetectionArray&)>& edit) {
  return rewritten_bag(name, [&](rosbag::Bag& out, const rosbag::MessageInstance& m) {
    const auto tags = m.instantiate<TagDetectionArray>();
    if (!tags) return copy(out, m);
    TagDetectionArray edited = *tags;
    edit(edited);
    out.write(m.getTopic(), m.getTime(), edited);
  });
}

// ------------------------------------------------------------------ the table

struct Case {
  std::string id;                             // as in docs/troubleshooting.md's test column
  std::function<std::string()> command;       // handeye arguments, without --output
  std::string error;                          // the error's name
  std::vector<std::string> mentions;          // where, and what to do
};

std::vector<Case> refusals() {
  const auto solve = [](const std::string& input, const std::string& extra = "") {
    return "solve --input " + input + " " + extra;
  };
  return {
      {"malformed_yaml", [=] { return solve(write("malformed.yaml", "setup: eye_in_hand\nsamples: [\n")); },
       "MalformedFile", {"malformed.yaml:"}},
      {"unknown_setup", [=] { return solve(write("setup.yaml", "setup: eye_on_hand\nsamples: []\n")); },
       "MalformedFile", {"eye_on_hand"}},
      {"missing_key", [=] { return solve(with_effector("missing.yaml", "{translation: [0.1, 0.2, 0.3]}")); },
       "MissingKey", {"samples[0].effector", "rotation"}},
      {"wrong_list_length", [=] { return solve(with_effector("length.yaml", "{translation: [0.1, 0.2], rotation: [0, 0, 0, 1]}")); },
       "WrongLength", {"samples[0].effector.translation", "exactly 3"}},
      {"nan", [=] { return solve(with_effector("nan.yaml", "{translation: [.nan, 0.2, 0.3], rotation: [0, 0, 0, 1]}")); },
       "NonFinite", {"samples[0].effector.translation[0]"}},
      {"inf", [=] { return solve(with_effector("inf.yaml", "{translation: [0.1, 0.2, 0.3], rotation: [-.inf, 0, 0, 1]}")); },
       "NonFinite", {"samples[0].effector.rotation[0]"}},
      {"quaternion_not_unit",
       [=] { return solve(with_effector("quat.yaml", "{translation: [0.1, 0.2, 0.3], rotation: [0.5, 0.5, 0.5, 0.9]}")); },
       "QuaternionNotUnit", {"samples[0].effector.rotation", "[qx, qy, qz, qw]"}},
      {"non_orthonormal_matrix",
       [=] { return solve(with_effector("matrix.yaml", "{matrix: [1, 0.02, 0, 0.1, 0, 1, 0, 0.2, 0, 0, 1, 0.3, 0, 0, 0, 1]}")); },
       "RotationNotOrthonormal", {"samples[0].effector.matrix", "det +1"}},
      {"invalid_noise", [=] { return solve(edited("noise.yaml", "rotation: [", "rotation: [-")); },
       "InvalidNoise", {"noise"}},
      {"too_few_samples", [=] { return solve(write("two.yaml", simulated(2))); }, "TooFewMotions", {"record more samples"}},
      {"pure_translation",
       [=] {
         SampleSet set = simulated(6);
         // The robot only translates; the camera sees what such poses show (a consistent session).
         const Eigen::Isometry3d X = typical_X(Setup::EyeInHand), Y = set.rig.pattern_pose(
             set.samples[0].T_base_effector, X, set.samples[0].T_camera_pattern);
         for (std::size_t i = 0; i < set.samples.size(); ++i) {
           PoseSample& s = set.samples[i];
           s.T_base_effector.linear() = set.samples[0].T_base_effector.linear();
           s.T_base_effector.translation() += Eigen::Vector3d(0.01, -0.02, 0.015) * static_cast<double>(i);
           s.T_camera_pattern = set.rig.predicted_view(s.T_base_effector, X, Y);
         }
         return solve(write("translation.yaml", set));
       },
       "PureTranslation", {"rotate"}},
      {"parallel_axes", [=] { return solve(write("parallel.yaml", about_one_axis())); }, "ParallelRotationAxes", {"second, different axis"}},
      {"rotations_below_noise",
       [=] {
         SampleSet set = simulated(6);
         set.noise->camera.rotation *= 1e6;  // 0.05 deg stated as 50 deg: the variance was given as sigma
         return solve(write("small.yaml", set), "--keep-outliers");
       },
       "RotationTooSmallForNoise", {"variances"}},
      {"angle_mismatch", [=] { return solve(write("flipped.yaml", with_flipped(1)), "--keep-outliers"); },
       "AngleMismatch", {"samples[0] -> samples[1]", "paired"}},
      {"too_many_outliers", [=] { return solve(write("outliers.yaml", with_flipped(6))); }, "TooManyOutliers", {"at most 5 may be dropped", "stamp pairing"}},
      {"noise_unidentifiable",
       [=] {
         Rng rng(3);
         MotionSet two = simulate_motions(rng, typical_X(Setup::EyeInHand), 2, test::sim_noise());
         two.noise.reset();
         return solve(write("two_motions.yaml", io::format_motions(two)));
       },
       "NoiseUnidentifiable", {"add a `noise` block"}},
      {"missing_input", [=] { return solve("/nonexistent/samples.yaml"); }, "IoError", {"/nonexistent/samples.yaml"}},
      {"bag_corrupt", [=] { return "bag --bag " + write("garbage.bag", "not a bag"); }, "IoError", {"garbage.bag"}},
      {"bag_wrong_topic", [=] { return "bag --bag " + clean_bag() + " --config " + write("topic.yaml", "detections_topic: /none\n"); },
       "NoData", {"/tag_detections"}},
      {"bag_without_tf",
       [=] {
         return "bag --bag " + rewritten_bag("notf.bag", [](rosbag::Bag& out, const rosbag::MessageInstance& m) {
                  if (m.getTopic() != "/tf") copy(out, m);
                });
       },
       "NoData", {"no TF"}},
      {"bag_wrong_frame",
       [=] { return "bag --bag " + with_detections("frame.bag", [](TagDetectionArray& a) {
                a.header.frame_id = "other_camera";
                for (auto& d : a.detections) d.pose.header.frame_id = "other_camera";
              }); },
       "NoData", {"other_camera", "tracking_base_frame"}},
      {"bag_wrong_tag",
       [=] { return "bag --config " + write("tag0.yaml", "tag_ids: [0]\n") + " --bag " +
                    with_detections("tag.bag", [](TagDetectionArray& a) {
                      for (auto& d : a.detections) d.id = {7};
                    }); },
       "NoData", {"tag_ids"}},
      {"compose_without_effector",
       [=] {
         const std::string truth = temp("compose_truth.yaml");
         EXPECT_EQ(run("sim --output " + temp("compose_samples.yaml") + " --truth " + truth + " --samples 5").exit_code, 0);
         return "compose --calibration " + truth + " --object 0,0,0.5,0,0,0,1 --object-sigma-mm 0.5 --object-sigma-deg 0.05";
       },
       "MissingKey", {"--effector"}},
  };
}

void PrintTo(const Case& c, std::ostream* os) { *os << c.id; }

class BadInput : public ::testing::TestWithParam<Case> {};

TEST_P(BadInput, RefusedWithANamedActionableErrorAndNoOutput) {
  const Case& c = GetParam();
  const std::string output = temp(c.id + "_result.yaml");
  std::ofstream(output) << kOldContent;
  const CliRun r = run(c.command() + " --output " + output);
  EXPECT_EQ(r.exit_code, 2) << r.out << r.err;
  EXPECT_NE(r.err.find(c.error), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("Fix:"), std::string::npos) << r.err;
  for (const std::string& m : c.mentions) EXPECT_NE(r.err.find(m), std::string::npos) << m << " in: " << r.err;
  EXPECT_EQ(io::read_file(output), kOldContent) << "the failed run changed " << output;
}

INSTANTIATE_TEST_SUITE_P(Table, BadInput, ::testing::ValuesIn(refusals()),
                         [](const ::testing::TestParamInfo<Case>& info) { return info.param.id; });

// ------------------------------------------------------------------ partly bad bags

/// X of `handeye bag` on a bag, and its summary.
struct BagResult {
  CliRun run;
  Isometry3d X;
  std::size_t samples = 0;
};

BagResult replay(const std::string& bag) {
  const std::string result = temp("replay_result.yaml"), samples = temp("replay_samples.yaml");
  BagResult r{run("bag --bag " + bag + " --output " + result + " --samples-out " + samples), Isometry3d::Identity()};
  if (r.run.exit_code == 0) {
    r.X = io::read_result(result).T_parent_camera().pose;
    r.samples = io::read_samples(samples).samples.size();
  }
  return r;
}

TEST(BadInputBag, LoopingBagGivesTheSameXAndSaysTheTimeJumpedBack) {
  const BagResult clean = replay(clean_bag());
  ASSERT_EQ(clean.run.exit_code, 0) << clean.run.err;
  const BagResult looped = replay(rewritten_bag("loop.bag", copy, 3));
  ASSERT_EQ(looped.run.exit_code, 0) << looped.run.err;
  EXPECT_EQ(looped.samples, clean.samples);
  EXPECT_LT((looped.X.matrix() - clean.X.matrix()).norm(), 1e-12);
  EXPECT_NE(looped.run.out.find("header stamps went back 2 time(s)"), std::string::npos) << looped.run.out;
  EXPECT_NE(looped.run.out.find("repeat a stamp already seen"), std::string::npos) << looped.run.out;
}

TEST(BadInputBag, DuplicateAndOutOfOrderDetectionsGiveTheSameX) {
  const BagResult clean = replay(clean_bag());
  ASSERT_EQ(clean.run.exit_code, 0) << clean.run.err;
  const BagResult duplicated = replay(rewritten_bag("dup.bag", [](rosbag::Bag& out, const rosbag::MessageInstance& m) {
    copy(out, m);
    if (m.getTopic() == "/tag_detections") copy(out, m);
  }));
  ASSERT_EQ(duplicated.run.exit_code, 0) << duplicated.run.err;
  EXPECT_EQ(duplicated.samples, clean.samples);
  EXPECT_LT((duplicated.X.matrix() - clean.X.matrix()).norm(), 1e-12);
  EXPECT_NE(duplicated.run.out.find("repeat a stamp already seen"), std::string::npos) << duplicated.run.out;

  // Pairs of detections swapped, as a multi-threaded detector may publish them.
  std::unique_ptr<rosbag::MessageInstance> held;
  const BagResult swapped = replay(rewritten_bag("swap.bag", [&](rosbag::Bag& out, const rosbag::MessageInstance& m) {
    if (m.getTopic() != "/tag_detections") return copy(out, m);
    if (!held) {
      held = std::make_unique<rosbag::MessageInstance>(m);
      return;
    }
    out.write(m.getTopic(), held->getTime(), m, m.getConnectionHeader());
    out.write(m.getTopic(), m.getTime(), *held, held->getConnectionHeader());
    held.reset();
  }));
  ASSERT_EQ(swapped.run.exit_code, 0) << swapped.run.err;
  EXPECT_EQ(swapped.samples, clean.samples);
  EXPECT_LT((swapped.X.matrix() - clean.X.matrix()).norm(), 1e-12);  // replayed in stamp order: the same samples
  EXPECT_NE(swapped.run.out.find("header stamps went back"), std::string::npos) << swapped.run.out;
}

TEST(BadInputBag, TfRecordedLateRefusesTheEarlyDetectionsWithTheReasonAndKeepsTheRest) {
  // `rosbag record` of /tf started after the camera's: no robot pose for the first 30%.
  const BagResult clean = replay(clean_bag());
  rosbag::Bag in(clean_bag(), rosbag::bagmode::Read);
  rosbag::View all(in);
  const ros::Time tf_start = all.getBeginTime() + (all.getEndTime() - all.getBeginTime()) * 0.3;
  const BagResult late = replay(rewritten_bag("late_tf.bag", [&](rosbag::Bag& out, const rosbag::MessageInstance& m) {
    if (m.getTopic() == "/tf" && m.getTime() < tf_start) return;
    copy(out, m);
  }));
  ASSERT_EQ(late.run.exit_code, 0) << late.run.err;
  EXPECT_NE(late.run.out.find("x no_robot_tf: no TF base_link -> tool0"), std::string::npos) << late.run.out;
  EXPECT_LT(late.samples, clean.samples);
  EXPECT_GE(late.samples, clean.samples - 3);
  EXPECT_LT((late.X.translation() - clean.X.translation()).norm(), 5e-3);
}

// ------------------------------------------------- docs/troubleshooting.md

/// Every row of every table in docs/troubleshooting.md ("What can go wrong")
/// names its test in the last column as `test/<file>`: `<name>`. A name in this
/// file is a row of the table above or a TEST of this file; elsewhere the file
/// must hold the name as a word (a TEST name, or the refusal kind the test checks).
TEST(BadInputReadme, EveryRowOfWhatCanGoWrongNamesAnExistingTest) {
  std::ifstream page(std::string(HANDEYE_SOURCE_DIR) + "/docs/troubleshooting.md");
  ASSERT_TRUE(page.good());
  std::set<std::string> table_ids;
  for (const Case& c : refusals()) table_ids.insert(c.id);
  const std::regex test_cell(R"(\| `(test/[A-Za-z0-9_.]+)`: `([A-Za-z0-9_]+)` \|$)");
  std::string line;
  bool titled = false;  // the page is the section: its title, then only its tables
  int rows = 0;
  while (std::getline(page, line)) {
    if (line.rfind("# ", 0) == 0) titled = line == "# What can go wrong";
    if (!titled || line.rfind("| ", 0) != 0 || line.find("| test |") != std::string::npos) continue;
    std::smatch m;
    if (!std::regex_search(line, m, test_cell)) {
      ADD_FAILURE() << "a row of docs/troubleshooting.md without a test (last column `test/<file>`: `<name>`): " << line;
      continue;
    }
    ++rows;
    const std::string file = m[1].str(), name = m[2].str();
    const std::string text = io::read_file(std::string(HANDEYE_SOURCE_DIR) + "/" + file);
    if (file == "test/test_bad_inputs.cpp") {
      EXPECT_TRUE(table_ids.count(name) || text.find(", " + name + ")") != std::string::npos)
          << name << " is neither a row of the bad-input table nor a TEST in " << file;
    } else {
      EXPECT_TRUE(std::regex_search(text, std::regex("\\b" + name + "\\b"))) << name << " is not in " << file;
    }
  }
  EXPECT_TRUE(titled) << "docs/troubleshooting.md lost its title `# What can go wrong`";
  EXPECT_GE(rows, 50) << "the page lost rows, or the parser lost the page";
}

}  // namespace
}  // namespace handeye
