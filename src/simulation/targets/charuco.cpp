// The ChArUco board as the renderer draws it (OpenCV's drawing), for its table
// (src/simulation/pattern_renderer.cpp).
#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>

#include "handeye_covariance/simulation/pattern_renderer.h"

namespace handeye {
namespace {

TargetPlanes draw(const Target& target, const RenderOptions& options) {
  const CharucoTarget& t = target.as<CharucoTarget>();
  const int texels = std::max(8, options.texels_per_square);
  // At the printer's resolution, within 8192 texels a side (a large board's
  // texels are large in metres, but so are its squares in the image).
  const double dots = options.print_dpi > 0.0 ? std::min(t.square / 0.0254 * options.print_dpi, 8192.0) : 0.0;
  const int printed = std::max(texels, std::min(static_cast<int>(dots), 8192 / std::max(t.columns, t.rows)));
  const int margin = std::max(1, static_cast<int>(std::lround(options.board_margin_squares * printed)));
  cv::Mat board;
  cv::copyMakeBorder(charuco_image(t, printed), board, margin, margin, margin, margin, cv::BORDER_CONSTANT,
                     cv::Scalar(255));
  const double margin_m = t.square * margin / printed;
  TargetPlanes out;
  out.planes.push_back({board, target_face(target),  // the middle of the squares, the texture's centre
                        t.columns * t.square + 2 * margin_m, t.rows * t.square + 2 * margin_m});
  return out;
}

}  // namespace

RenderKind charuco_render() { return {"charuco", draw}; }

}  // namespace handeye
