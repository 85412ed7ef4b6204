// The ChArUco kind (core/target.h): `type: charuco` files.
// Frame (OpenCV's, vision/aruco.h): origin at the board's top-left corner, x
// along a row, y down, z into the board.
#pragma once

#include <string>

#include "handeye_covariance/core/target.h"

namespace handeye {

struct CharucoTarget {
  int columns = 0, rows = 0;  // squares along a row, and along a column
  double square = 0.0;        // m, a square's edge
  double marker = 0.0;        // m, a marker's edge (black border included)
  std::string dictionary = "DICT_6X6_250";
};

const TargetKind& charuco_kind();
Target make_target(const CharucoTarget& charuco);

}  // namespace handeye
