// The chessboard's detector (vision/chessboard.h), for the vision table (src/vision/target.cpp).
#include "handeye_covariance/vision/chessboard.h"
#include "handeye_covariance/vision/target.h"

namespace handeye {
namespace {

class ChessboardDetector : public KindDetector {
 public:
  explicit ChessboardDetector(const ChessboardTarget& target) : target_(target) {}
  TargetObservation detect(const cv::Mat& gray) const override { return detect_chessboard(gray, target_); }

 private:
  ChessboardTarget target_;
};

}  // namespace

VisionKind chessboard_vision() {
  return {"chessboard",
          [](const Target& target, const std::string& where) { check_chessboard(target.as<ChessboardTarget>(), where); },
          [](const Target& target, const TargetDetectorOptions&) -> std::unique_ptr<KindDetector> {
            return std::make_unique<ChessboardDetector>(target.as<ChessboardTarget>());
          }};
}

}  // namespace handeye
