// The calibration pattern as the detector sees it: one AprilTag or a board
// (bundle) of tags at known poses in the pattern frame.
//
// Frames (OpenCV's board convention, and the simulator's): a tag's frame has its
// origin at the tag centre, x to the right of the printed tag, y up, z out of the
// printed face towards a camera that sees it. `size` is the edge of the tag's
// black square (apriltag's convention), not of the white quiet zone around it.
// The pattern frame is the layout's own; put its origin near the middle of the
// board, so that the detector's rotation and translation errors stay nearly
// uncorrelated (the estimator weights them as independent, see docs/troubleshooting.md, "Limits that are not errors").
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <string>
#include <vector>

namespace handeye {

struct TagPlacement {
  int id = 0;
  double size = 0.0;  // m, black square edge
  Eigen::Isometry3d T_pattern_tag = Eigen::Isometry3d::Identity();

  /// The four corners of the black square in the pattern frame, in the order the
  /// detector reports them (tag_detector.h): bottom-left, bottom-right,
  /// top-right, top-left as seen on the printed tag.
  std::array<Eigen::Vector3d, 4> corners() const;
};

struct TagLayout {
  std::string family = "tag36h11";
  std::vector<TagPlacement> tags;

  /// The placement of tag `id`, or nullptr when it is not part of the pattern.
  const TagPlacement* find(int id) const;
  std::vector<int> ids() const;
};

/// One tag of edge `size` whose centre is the pattern origin.
TagLayout single_tag_layout(int id, double size, const std::string& family = "tag36h11");

/// Throws HandEyeError (InvalidLayout) on no tags, a non-positive or non-finite
/// size, or a duplicate id; `where` names the source for the message.
void check_layout(const TagLayout& layout, const std::string& where);

}  // namespace handeye
