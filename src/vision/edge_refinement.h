// The edge-fit refinement of a square marker's corners, shared by the ArUco and
// AprilTag detectors (internal to the vision library).
#pragma once

#include <array>

#include <Eigen/Core>
#include <opencv2/core.hpp>

namespace handeye {

/// libapriltag's edge refinement (refine_edges in apriltag.c), which the edge-fit
/// corner model describes, repeated until the corners stop moving (< 0.001 px,
/// at most 10 passes). One pass searches +-2 px about the current lines, so it
/// keeps part of its start's error: measured on rendered views (test_targets),
/// from OpenCV's corners (about 0.5 px inside) two passes leave them 0.011 px
/// inside on average, a depth bias of 0.15 mm for a 0.1 m marker at 0.6 m that
/// the covariance cannot know, and four or five leave 0.0004 px; from
/// libapriltag's own single pass, a shift of about -0.002 px in x and y that is
/// shared by every corner of every image (a bias of X, rendered sessions in
/// corners_study). `corners` in OpenCV's pixel convention (centres at
/// integers), consecutive around the marker. Returns false (corners untouched
/// or partly moved) when a side has too few edge points (the marker at the
/// image border) or the lines do not meet near the corners.
bool refine_marker_edges(const cv::Mat& gray, std::array<Eigen::Vector2d, 4>& corners);

}  // namespace handeye
