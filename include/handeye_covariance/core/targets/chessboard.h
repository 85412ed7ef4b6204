// The chessboard kind (core/target.h): `type: chessboard` files.
// Frame (OpenCV's, vision/chessboard.h): origin at the first inner corner, x
// along a row, y down the rows, z into the board.
#pragma once

#include "handeye_covariance/core/target.h"

namespace handeye {

struct ChessboardTarget {
  int columns = 0, rows = 0;  // inner corners along a row, and along a column
  double square = 0.0;        // m, the edge of one square
};

const TargetKind& chessboard_kind();
Target make_target(const ChessboardTarget& chessboard);

}  // namespace handeye
