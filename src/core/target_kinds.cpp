// The one list of target kinds (core/target.h). A new kind: its file in
// core/targets/ and a line here; then a line in each layer's table
// (src/vision/target.cpp, src/simulation/pattern_renderer.cpp,
// src/print/target_printer.cpp). docs/targets.md, "Adding a target kind".
#include "handeye_covariance/core/target.h"
#include "handeye_covariance/core/targets/charuco.h"
#include "handeye_covariance/core/targets/chessboard.h"
#include "handeye_covariance/core/targets/markers.h"

namespace handeye {

const std::vector<const TargetKind*>& target_kinds() {
  // The order of the messages that list them.
  static const std::vector<const TargetKind*> kinds = {&chessboard_kind(), &charuco_kind(), &aruco_kind(),
                                                       &apriltag_kind()};
  return kinds;
}

}  // namespace handeye
