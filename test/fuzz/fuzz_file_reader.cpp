// libFuzzer target for one kind of user file, built once per kind so that each
// reader gets its own 10^6 inputs (fuzz_yaml_readers runs every reader on the same
// bytes, at a fraction of the rate). A reader may only return or throw
// HandEyeError; anything else (another exception, a crash, a leak, undefined
// behaviour under UBSan) is a bug.
//   HANDEYE_FUZZ_TARGET_FILES  fuzz_target_files:  io::parse_target (every target kind, tag layouts)
//   HANDEYE_FUZZ_CAMERA_FILES  fuzz_camera_files:  io::parse_camera_info and OpenCV's files (cv::FileStorage)
//   HANDEYE_FUZZ_POSE_FILES    fuzz_pose_files:    io::parse_robot_pose (YAML, JSON, ViSP, 4x4 text) and the CSV table
// Seeds: test/fuzz/corpus/files. Short runs in ./scripts/test; the long runs in docs/evidence.md.
#include <cstdint>
#include <string>

#include "handeye_covariance/core/errors.h"
#include "named_errors_only.h"
#include "handeye_covariance/io/yaml_io.h"
#ifdef HANDEYE_FUZZ_CAMERA_FILES
#include "handeye_covariance/images/image_folder.h"
#endif

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace handeye;
  const std::string text(reinterpret_cast<const char*>(data), size);
#if defined(HANDEYE_FUZZ_TARGET_FILES)
  named_errors_only([&] {
    const Target target = io::parse_target(text, "fuzz");
    (void)target.describe();  // what `handeye images` prints next
  });
#elif defined(HANDEYE_FUZZ_CAMERA_FILES)
  named_errors_only([&] { io::parse_camera_info(text, "fuzz"); });
  named_errors_only([&] { images::parse_opencv_camera(text, "fuzz"); });
#elif defined(HANDEYE_FUZZ_POSE_FILES)
  named_errors_only([&] { io::parse_robot_pose(text, "fuzz"); });
  named_errors_only([&] { io::parse_pose_table(text, "fuzz"); });
#else
#error "define one of HANDEYE_FUZZ_TARGET_FILES, HANDEYE_FUZZ_CAMERA_FILES, HANDEYE_FUZZ_POSE_FILES"
#endif
  return 0;
}
