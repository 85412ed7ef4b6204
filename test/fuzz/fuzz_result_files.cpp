// libFuzzer target for the results family (src/io/result_file.cpp): result files,
// stored calibrations (ours and easy_handeye's) and pose files with a covariance,
// on the same bytes. A reader may only return or throw HandEyeError; anything else
// (another exception, a crash, a leak, undefined behaviour under UBSan) is a bug.
// What a reader accepts goes where a tool sends it next: a result into the
// object-pose chain (eq. 68), a stored calibration to TF. Seeds:
// test/fuzz/corpus/result_files. Short run in ./scripts/test; long run in docs/evidence.md.
#include <cstdint>
#include <cstdlib>
#include <string>

#include "handeye_covariance/core/errors.h"
#include "named_errors_only.h"
#include "handeye_covariance/core/object_pose.h"
#include "handeye_covariance/io/result_file.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace handeye;
  const std::string text(reinterpret_cast<const char*>(data), size);
  named_errors_only([&] {
    const io::CalibrationFile c = io::parse_result(text, "fuzz");
    ObjectPoseInput in;
    in.X = c.T_parent_camera();
    in.T_camera_object = c.T_parent_camera();
    in.T_base_effector = c.T_parent_camera();
    named_errors_only([&] { object_in_base(in); });
  });
  named_errors_only([&] {
    // What publish.launch reads: ours or easy_handeye's; what it accepts goes to TF as it is.
    const io::StoredCalibration stored = io::parse_stored_calibration(text, "fuzz");
    if (!stored.T_parent_camera.pose.matrix().allFinite()) std::abort();
  });
  named_errors_only([&] { io::parse_pose_file(text, "fuzz"); });
  return 0;
}
