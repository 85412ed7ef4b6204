// ArUco markers' detector (vision/aruco.h), for the vision table (src/vision/target.cpp).
#include "handeye_covariance/vision/aruco.h"
#include "handeye_covariance/vision/target.h"

namespace handeye {

VisionKind aruco_vision() {
  return {"aruco", [](const Target& target, const std::string& where) { check_markers(target.as<TagLayout>(), where); },
          [](const Target& target, const TargetDetectorOptions& options) -> std::unique_ptr<KindDetector> {
            const TagLayout& layout = target.as<TagLayout>();
            return std::make_unique<MarkerLayoutDetector<ArucoDetector>>(layout, options.pose, "dictionary", layout.family);
          }};
}

}  // namespace handeye
