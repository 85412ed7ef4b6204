// libFuzzer target: every YAML reader of the package on the same bytes. A
// reader may only return or throw HandEyeError (a named, actionable error);
// anything else (another exception, a crash, a leak, undefined behaviour under
// UBSan) is a bug. Readers that accept the input are followed by what a tool
// would do next, on small inputs: the estimator (samples, motions) or the
// object-pose chain (a result and a pose).
//
// Built twice: fuzz_yaml_readers (readers, then the estimator) and, with
// HANDEYE_FUZZ_READERS_ONLY, fuzz_yaml_parse (readers and the write/read round
// trip only). The estimator on small sets runs at ~100 exec/s under ASan, which
// makes 10^6 inputs a 3-hour run; the parse-only build reaches 10^6 in minutes
// and covers the byte-level parsing, where crashes would come from.
//
// Short run (./scripts/test):  fuzz_yaml_readers -runs=10000 test/fuzz/corpus/yaml
// Long run (documented):      fuzz_yaml_parse -runs=1000000 <a copy of the corpus>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "handeye_covariance/core/errors.h"
#include "named_errors_only.h"
#include "handeye_covariance/core/object_pose.h"
#include "handeye_covariance/estimation/outliers.h"
#include "handeye_covariance/io/yaml_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace handeye;
  const std::string text(reinterpret_cast<const char*>(data), size);
  named_errors_only([&] {
    const SampleSet s = io::parse_samples(text, "fuzz");
#ifndef HANDEYE_FUZZ_READERS_ONLY
    if (s.samples.size() <= 8) named_errors_only([&] { solve_robust(s); });
#endif
    io::parse_samples(io::format_samples(s), "round trip");  // what we write, we read
  });
  named_errors_only([&] {
    const MotionSet m = io::parse_motions(text, "fuzz");
#ifndef HANDEYE_FUZZ_READERS_ONLY
    if (m.motions.size() <= 8) named_errors_only([&] { solve(m); });
#endif
    io::parse_motions(io::format_motions(m), "round trip");
  });
  named_errors_only([&] {
    const io::CalibrationFile c = io::parse_result(text, "fuzz");
    ObjectPoseInput in;
    in.X = c.T_parent_camera;
    in.T_camera_object = c.T_parent_camera;
    in.T_base_effector = c.T_parent_camera;
#ifndef HANDEYE_FUZZ_READERS_ONLY
    named_errors_only([&] { object_in_base(in); });
#endif
  });
  named_errors_only([&] {
    // What publish.launch reads: ours or easy_handeye's; what it accepts goes to TF as it is.
    const io::StoredCalibration stored = io::parse_stored_calibration(text, "fuzz");
    if (!stored.T_parent_camera.pose.matrix().allFinite()) std::abort();
  });
  named_errors_only([&] { io::parse_pose_file(text, "fuzz"); });
  named_errors_only([&] { io::parse_candidate_poses(text, "fuzz"); });
  named_errors_only([&] { io::parse_tag_layout(text, "fuzz"); });
  named_errors_only([&] { io::parse_robot_pose(text, "fuzz"); });
  named_errors_only([&] { io::parse_pose_table(text, "fuzz"); });
  named_errors_only([&] { io::parse_target(text, "fuzz"); });
  named_errors_only([&] { io::parse_camera_info(text, "fuzz"); });
  return 0;
}
