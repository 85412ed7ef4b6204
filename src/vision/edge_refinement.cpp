#include "edge_refinement.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include <Eigen/Dense>

namespace handeye {
namespace {

/// Keys' cubic convolution kernel (a = -0.5, exact for quadratics).
double keys_weight(double t) {
  t = std::abs(t);
  if (t < 1.0) return (1.5 * t - 2.5) * t * t + 1.0;
  if (t < 2.0) return ((-0.5 * t + 2.5) * t - 4.0) * t + 2.0;
  return 0.0;
}

/// Bicubic gray level (Keys), or NaN where its 4 x 4 support leaves the image.
/// Not bilinear: a linear interpolant of a blurred edge pulls the gradient-weighted
/// mean towards pixel centres (pixel locking), and where an edge runs along the
/// pixel grid every point on it shares that pull. Noise-free rendered 2 x 2 boards
/// at 0.85-1.0 m (corners_study, 6 sessions): corners 0.0019 px outwards from each
/// tag's centre and X 0.027 mm RMS off bilinearly; 0.0006 px and 0.018 mm bicubically.
/// Not cv::remap with INTER_CUBIC either: it rounds positions to 1/32 px.
double sample(const cv::Mat& gray, const Eigen::Vector2d& p) {
  const int x = static_cast<int>(std::floor(p.x())), y = static_cast<int>(std::floor(p.y()));
  if (x < 1 || y < 1 || x + 2 >= gray.cols || y + 2 >= gray.rows) return std::nan("");
  std::array<double, 4> wx, wy;  // the four columns' and rows' weights, once each
  for (int k = 0; k < 4; ++k) {
    wx[k] = keys_weight(p.x() - (x + k - 1));
    wy[k] = keys_weight(p.y() - (y + k - 1));
  }
  double value = 0.0;
  for (int j = 0; j < 4; ++j) {
    const std::uint8_t* row = gray.ptr<std::uint8_t>(y + j - 1);
    double across = 0.0;
    for (int i = 0; i < 4; ++i) across += wx[i] * row[x + i - 1];
    value += wy[j] * across;
  }
  return value;
}

/// libapriltag's edge refinement (refine_edges in apriltag.c), which the edge-fit
/// corner model describes: along each side of the black square, at one point per
/// 4 px (at least 16), the edge's position across the side is the gradient-weighted
/// mean within +-`range` px (libapriltag: quad_decimate + 1); a line is fitted to
/// those points, and each corner is where two lines meet. Returns false (corners
/// untouched) when a side has too few edge points (the marker at the image border).
bool refine_marker_corners(const cv::Mat& gray, std::array<Eigen::Vector2d, 4>& corners, double range,
                           bool dark_inside) {
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();
  for (const Eigen::Vector2d& c : corners) centre += 0.25 * c;
  std::array<Eigen::Vector2d, 4> point_on, direction;  // the four fitted lines
  for (int e = 0; e < 4; ++e) {
    const Eigen::Vector2d a = corners[e], b = corners[(e + 1) % 4];
    const double length = (b - a).norm();
    if (!(length > 4.0)) return false;
    const Eigen::Vector2d along = (b - a) / length;
    Eigen::Vector2d normal(-along.y(), along.x());
    if (normal.dot(0.5 * (a + b) - centre) < 0.0) normal = -normal;  // outwards
    if (!dark_inside) normal = -normal;  // from dark to bright, as libapriltag's reversed_border
    const int samples = std::max(16, static_cast<int>(length / 4.0));
    std::vector<Eigen::Vector2d> edge;
    for (int i = 0; i < samples; ++i) {
      const Eigen::Vector2d p = a + (b - a) * ((i + 1.0) / (samples + 1.0));
      double weight_sum = 0.0, offset_sum = 0.0;
      for (double n = -range; n <= range; n += 0.25) {
        const double outer = sample(gray, p + (n + 1.0) * normal), inner = sample(gray, p + (n - 1.0) * normal);
        if (!(outer > inner)) continue;  // NaN outside the image, or a gradient the wrong way
        const double w = (outer - inner) * (outer - inner);
        weight_sum += w;
        offset_sum += w * n;
      }
      if (weight_sum > 0.0) edge.push_back(p + (offset_sum / weight_sum) * normal);
    }
    if (edge.size() < 8) return false;
    Eigen::Vector2d mean = Eigen::Vector2d::Zero();
    for (const Eigen::Vector2d& q : edge) mean += q / static_cast<double>(edge.size());
    Eigen::Matrix2d scatter = Eigen::Matrix2d::Zero();
    for (const Eigen::Vector2d& q : edge) scatter += (q - mean) * (q - mean).transpose();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(scatter);
    point_on[e] = mean;
    direction[e] = eig.eigenvectors().col(1);
  }
  std::array<Eigen::Vector2d, 4> refined;
  for (int c = 0; c < 4; ++c) {
    const int previous = (c + 3) % 4;  // corner c is where side c - 1 ends and side c starts
    Eigen::Matrix2d A;
    A << direction[previous], -direction[c];
    if (std::abs(A.determinant()) < 1e-6) return false;
    const Eigen::Vector2d st = A.lu().solve(point_on[c] - point_on[previous]);
    refined[c] = point_on[previous] + st(0) * direction[previous];
    if (!((refined[c] - corners[c]).norm() < 3.0)) return false;  // not the same corner
  }
  corners = refined;
  return true;
}

}  // namespace

bool refine_marker_edges(const cv::Mat& gray, std::array<Eigen::Vector2d, 4>& corners, double settled_range,
                         bool dark_inside) {
  double moved = std::numeric_limits<double>::infinity();
  for (int pass = 0; pass < 10; ++pass) {
    const std::array<Eigen::Vector2d, 4> before = corners;
    const double range = moved < 0.05 ? settled_range : 2.0;  // the lines within 0.05 px: the window may narrow
    if (!refine_marker_corners(gray, corners, range, dark_inside)) return false;
    moved = 0.0;
    for (int c = 0; c < 4; ++c) moved = std::max(moved, (corners[c] - before[c]).norm());
    if (range == settled_range && moved < 1e-3) break;
  }
  return true;
}

}  // namespace handeye
