// ArUco markers' detector (vision/aruco.h), for the vision table (src/vision/target.cpp).
#include "handeye_covariance/vision/aruco.h"
#include "handeye_covariance/vision/target.h"

namespace handeye {
namespace {

class MarkersDetector : public KindDetector {
 public:
  MarkersDetector(const TagLayout& layout, const PatternPoseOptions& options)
      : layout_(layout), options_(options), detector_(layout.family) {}
  TargetObservation detect(const cv::Mat& gray) const override {
    return marker_observation(layout_, detector_.detect(gray), options_, "dictionary");
  }

 private:
  TagLayout layout_;
  PatternPoseOptions options_;
  ArucoDetector detector_;
};

}  // namespace

VisionKind aruco_vision() {
  return {"aruco", [](const Target& target, const std::string& where) { check_markers(target.as<TagLayout>(), where); },
          [](const Target& target, const TargetDetectorOptions& options) -> std::unique_ptr<KindDetector> {
            return std::make_unique<MarkersDetector>(target.as<TagLayout>(), options.pose);
          }};
}

}  // namespace handeye
