// AprilTags' detector (vision/tag_detector.h, libapriltag), for the vision table (src/vision/target.cpp).
#include "handeye_covariance/vision/tag_detector.h"
#include "handeye_covariance/vision/target.h"

namespace handeye {
namespace {

TagDetectorOptions with_family(TagDetectorOptions options, const std::string& family) {
  options.family = family;
  return options;
}

class MarkersDetector : public KindDetector {
 public:
  MarkersDetector(const TagLayout& layout, const TargetDetectorOptions& options)
      : layout_(layout), options_(options.pose), detector_(with_family(options.apriltag, layout.family)) {}
  TargetObservation detect(const cv::Mat& gray) const override {
    return marker_observation(layout_, detector_.detect(gray), options_, "family");
  }

 private:
  TagLayout layout_;
  PatternPoseOptions options_;
  TagDetector detector_;
};

}  // namespace

VisionKind apriltag_vision() {
  return {"apriltag", [](const Target& target, const std::string& where) { check_markers(target.as<TagLayout>(), where); },
          [](const Target& target, const TargetDetectorOptions& options) -> std::unique_ptr<KindDetector> {
            return std::make_unique<MarkersDetector>(target.as<TagLayout>(), options);
          }};
}

}  // namespace handeye
