// libFuzzer target for the targets family (src/io/target_file.cpp): target files
// (every kind), tag layouts, ROS camera_info and OpenCV's camera files
// (images/camera_file.cpp; cv::FileStorage is not instrumented, our code around
// it is), on the same bytes. A reader may only return or throw HandEyeError;
// anything else (another exception, a crash, a leak, undefined behaviour under
// UBSan) is a bug. Seeds: test/fuzz/corpus/target_files. Short run in
// ./scripts/test; long run in docs/evidence.md.
#include <cstdint>
#include <string>

#include "handeye_covariance/core/errors.h"
#include "named_errors_only.h"
#include "handeye_covariance/images/image_folder.h"
#include "handeye_covariance/io/target_file.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace handeye;
  const std::string text(reinterpret_cast<const char*>(data), size);
  named_errors_only([&] {
    const Target target = io::parse_target(text, "fuzz");
    (void)target.describe();  // what `handeye images` prints next
  });
  named_errors_only([&] { io::parse_tag_layout(text, "fuzz"); });
  named_errors_only([&] { io::parse_camera_info(text, "fuzz"); });
  named_errors_only([&] { images::parse_opencv_camera(text, "fuzz"); });
  return 0;
}
