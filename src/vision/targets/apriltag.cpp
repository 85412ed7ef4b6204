// AprilTags' detector (vision/tag_detector.h, libapriltag), for the vision table (src/vision/target.cpp).
#include "handeye_covariance/vision/tag_detector.h"
#include "handeye_covariance/vision/target.h"

namespace handeye {
namespace {

TagDetectorOptions with_family(TagDetectorOptions options, const std::string& family) {
  options.family = family;
  return options;
}

}  // namespace

VisionKind apriltag_vision() {
  return {"apriltag", [](const Target& target, const std::string& where) { check_markers(target.as<TagLayout>(), where); },
          [](const Target& target, const TargetDetectorOptions& options) -> std::unique_ptr<KindDetector> {
            const TagLayout& layout = target.as<TagLayout>();
            return std::make_unique<MarkerLayoutDetector<TagDetector>>(layout, options.pose, "family",
                                                                       with_family(options.apriltag, layout.family));
          }};
}

}  // namespace handeye
