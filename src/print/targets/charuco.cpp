// The ChArUco board on paper, for the printer's table (src/print/target_printer.cpp).
#include <cmath>
#include <set>
#include <utility>

#include "handeye_covariance/print/target_printer.h"
#include "handeye_covariance/vision/aruco.h"

namespace handeye {
namespace print {
namespace {

// OpenCV's board frame is the page's (x right, y down); its markers sit in
// the white squares, every other square is black.
PrintedBoard draw(const Target& target) {
  const CharucoTarget& t = target.as<CharucoTarget>();
  const TagLayout markers = charuco_marker_layout(t);
  std::set<std::pair<int, int>> white;
  for (const TagPlacement& tag : markers.tags) {
    const Eigen::Vector3d c = tag.T_pattern_tag.translation();
    white.emplace(static_cast<int>(std::floor(c.y() / t.square)), static_cast<int>(std::floor(c.x() / t.square)));
  }
  PrintedBoard board;
  for (int r = 0; r < t.rows; ++r) {
    for (int c = 0; c < t.columns; ++c) {
      if (white.count({r, c})) continue;
      const Eigen::Vector2d min(c * t.square, r * t.square);
      board.black_squares.emplace_back(min, min + Eigen::Vector2d(t.square, t.square));
    }
  }
  board.extent = Eigen::AlignedBox2d(Eigen::Vector2d::Zero(), Eigen::Vector2d(t.columns, t.rows) * t.square);
  add_markers(markers, Eigen::Isometry3d::Identity(), board);
  return board;
}

}  // namespace

PrintKind charuco_print() { return {"charuco", draw}; }

}  // namespace print
}  // namespace handeye
