// The one list of target kinds (core/target.h). A new kind: its file in
// core/targets/ and a line here; then a line in each layer's table
// (src/vision/target.cpp, src/simulation/pattern_renderer.cpp,
// src/print/target_printer.cpp). docs/targets.md, "Adding a target kind".
#include "handeye_covariance/core/target.h"

#include "handeye_covariance/core/errors.h"
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

void throw_no_layer_entry(const std::string& name, const std::string& missing, const std::string& layer,
                          const std::string& entry_type, const std::string& table_file) {
  throw HandEyeError(ErrorCode::InvalidLayout, "the target kind `" + name + "` has no " + missing, layer,
                     "list its " + entry_type + " in " + table_file + " (docs/targets.md, \"Adding a target kind\")");
}

}  // namespace handeye
