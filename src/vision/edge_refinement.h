// The edge-fit refinement of a square marker's corners, shared by the ArUco and
// AprilTag detectors (internal to the vision library).
#pragma once

#include <array>

#include <Eigen/Core>
#include <opencv2/core.hpp>

namespace handeye {

/// libapriltag's edge refinement (refine_edges in apriltag.c), which the edge-fit
/// corner model describes, repeated until the corners stop moving (< 0.001 px,
/// at most 10 passes). A pass finds each edge point within +-2 px of the current
/// lines, so one pass keeps part of its start's error: from OpenCV's corners
/// (about 0.5 px inside) two passes leave them 0.011 px inside on average, four
/// or five 0.0004 px (test_targets); libapriltag's own single pass (nearest-pixel
/// samples within +-(quad_decimate + 1) px of its thresholded quad) leaves
/// (-0.0025, -0.0034) px on average, the same for every corner of every view
/// (test_vision). Once the lines are within 0.05 px the window is
/// +-`settled_range` px.
///
/// Why the window may narrow: the gradients within +-2 px also see the border's
/// inner side, where white data cells lighten it, and the fitted edge moves
/// outwards. Measured on rendered sessions (corners_study, mean outward shift per
/// corner, noise-free, 0.4-1.0 m, bicubic samples): a 2 x 2 board of 60 mm
/// AprilTags 0.0008 px with +-2 px, 0.0003 with +-1.5, 0.0002 with +-1; one 48 mm
/// tag (cells 3.6 px wide at 1 m) 0.0059, 0.0037, 0.0017. Bilinear samples gave
/// 0.0006 on the board and 0.0036 on the single tag with +-1 px, and with +-1 px
/// shifted single 0.1 m ArUco markers at 0.4-0.8 m inwards (0.0010-0.0015 px;
/// test_images: one ArUco marker's NEES of X 9.9 against 8.1 with +-2). The
/// AprilTag detector narrows the window, the ArUco detector keeps +-2 px.
///
/// `corners` in OpenCV's pixel convention (centres at integers), consecutive
/// around the marker; `dark_inside` false for a square brighter than around it
/// (libapriltag's reversed_border families). Returns false (corners untouched or
/// partly moved) when a side has too few edge points (the marker at the image
/// border) or the lines do not meet near the corners.
bool refine_marker_edges(const cv::Mat& gray, std::array<Eigen::Vector2d, 4>& corners, double settled_range,
                         bool dark_inside = true);

}  // namespace handeye
