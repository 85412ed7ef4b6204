// libFuzzer target for the robot poses family (src/io/pose_files.cpp): a robot pose
// file in every format (YAML, JSON, ViSP, 4x4 text) and the CSV pose table, on the
// same bytes. A reader may only return or throw HandEyeError; anything else
// (another exception, a crash, a leak, undefined behaviour under UBSan) is a bug.
// Seeds: test/fuzz/corpus/pose_files. Short run in ./scripts/test; long run in docs/evidence.md.
#include <cstdint>
#include <string>

#include "handeye_covariance/core/errors.h"
#include "named_errors_only.h"
#include "handeye_covariance/io/pose_files.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace handeye;
  const std::string text(reinterpret_cast<const char*>(data), size);
  named_errors_only([&] { io::parse_robot_pose(text, "fuzz"); });
  named_errors_only([&] { io::parse_pose_table(text, "fuzz"); });
  return 0;
}
