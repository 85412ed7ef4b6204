// The chessboard as the renderer draws it, for its table (src/simulation/pattern_renderer.cpp).
#include <algorithm>
#include <cmath>

#include "handeye_covariance/simulation/pattern_renderer.h"

namespace handeye {
namespace {

/// A chessboard of `t`, `texels` to a square, with `margin` white squares around:
/// square (r, c) of the (rows + 1) x (columns + 1) is black when r + c is odd (the
/// square outside the first inner corner is white: OpenCV's origin, chessboard.h).
cv::Mat chessboard_texture(const ChessboardTarget& t, int texels, int margin) {
  cv::Mat board((t.rows + 1 + 2 * margin) * texels, (t.columns + 1 + 2 * margin) * texels, CV_8UC1, cv::Scalar(255));
  for (int r = 0; r < t.rows + 1; ++r) {
    for (int c = 0; c < t.columns + 1; ++c) {
      if ((r + c) % 2 == 0) continue;
      board(cv::Rect((margin + c) * texels, (margin + r) * texels, texels, texels)).setTo(0);
    }
  }
  return board;
}

TargetPlanes draw(const Target& target, const RenderOptions& options) {
  const ChessboardTarget& t = target.as<ChessboardTarget>();
  const int texels = std::max(8, options.texels_per_square);
  // A whole number of white squares around, at least the margin asked for.
  const int margin = std::max(1, static_cast<int>(std::ceil(options.board_margin_squares)));
  // The texture's centre is the board's face (target_face: the middle of its inner corners).
  TargetPlanes out;
  out.planes.push_back({chessboard_texture(t, texels, margin), target_face(target),
                        (t.columns + 1 + 2 * margin) * t.square, (t.rows + 1 + 2 * margin) * t.square});
  return out;
}

}  // namespace

RenderKind chessboard_render() { return {"chessboard", draw}; }

}  // namespace handeye
