// The ChArUco board's detector (vision/aruco.h), for the vision table (src/vision/target.cpp).
#include "handeye_covariance/vision/aruco.h"
#include "handeye_covariance/vision/target.h"

namespace handeye {
namespace {

class CharucoDetector : public KindDetector {
 public:
  CharucoDetector(const CharucoTarget& target, int min_corners) : target_(target), min_corners_(min_corners) {}
  TargetObservation detect(const cv::Mat& gray) const override { return detect_charuco(gray, target_, min_corners_); }

 private:
  CharucoTarget target_;
  int min_corners_;
};

}  // namespace

VisionKind charuco_vision() {
  return {"charuco",
          [](const Target& target, const std::string& where) { check_charuco(target.as<CharucoTarget>(), where); },
          [](const Target& target, const TargetDetectorOptions& options) -> std::unique_ptr<KindDetector> {
            return std::make_unique<CharucoDetector>(target.as<CharucoTarget>(), options.min_charuco_corners);
          }};
}

}  // namespace handeye
