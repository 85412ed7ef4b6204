// The chessboard on paper, for the printer's table (src/print/target_printer.cpp).
#include "handeye_covariance/core/targets/chessboard.h"
#include "handeye_covariance/print/target_printer.h"

namespace handeye {
namespace print {
namespace {

// (columns + 1) x (rows + 1) squares, the top-left one white (the origin's
// outer diagonal square, vision/chessboard.h). The white the detector needs
// around the board is the page's margin and the gap above the footer.
PrintedBoard draw(const Target& target) {
  const ChessboardTarget& t = target.as<ChessboardTarget>();
  const double s = t.square;
  PrintedBoard board;
  for (int r = 0; r <= t.rows; ++r) {
    for (int c = 0; c <= t.columns; ++c) {
      if ((r + c) % 2 == 0) continue;
      const Eigen::Vector2d min((c - 1) * s, (r - 1) * s);
      board.black_squares.emplace_back(min, min + Eigen::Vector2d(s, s));
    }
  }
  board.extent = Eigen::AlignedBox2d(Eigen::Vector2d(-s, -s), Eigen::Vector2d(t.columns * s, t.rows * s));
  return board;
}

}  // namespace

PrintKind chessboard_print() { return {"chessboard", draw}; }

}  // namespace print
}  // namespace handeye
