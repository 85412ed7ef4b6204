#include "handeye_covariance/core/tag_layout.h"

#include <cmath>
#include <set>

#include "handeye_covariance/core/errors.h"

namespace handeye {

std::array<Eigen::Vector3d, 4> TagPlacement::corners() const {
  const double h = 0.5 * size;
  // libapriltag reports the corners counter-clockwise in the image (y down)
  // starting at the bottom-left of the printed tag; the order is checked
  // against rendered images in test_vision.
  return {T_pattern_tag * Eigen::Vector3d(-h, -h, 0.0), T_pattern_tag * Eigen::Vector3d(h, -h, 0.0),
          T_pattern_tag * Eigen::Vector3d(h, h, 0.0), T_pattern_tag * Eigen::Vector3d(-h, h, 0.0)};
}

const TagPlacement* TagLayout::find(int id) const {
  for (const TagPlacement& tag : tags) {
    if (tag.id == id) return &tag;
  }
  return nullptr;
}

std::vector<int> TagLayout::ids() const {
  std::vector<int> ids;
  for (const TagPlacement& tag : tags) ids.push_back(tag.id);
  return ids;
}

TagLayout single_tag_layout(int id, double size, const std::string& family) {
  TagLayout layout;
  layout.family = family;
  layout.tags.push_back({id, size, Eigen::Isometry3d::Identity()});
  check_layout(layout, "single tag " + std::to_string(id));
  return layout;
}

void check_layout(const TagLayout& layout, const std::string& where) {
  if (layout.tags.empty()) {
    throw HandEyeError(ErrorCode::InvalidLayout, "the pattern has no tags", where,
                       "list at least one tag as {id: 0, size: 0.06}");
  }
  std::set<int> seen;
  for (std::size_t i = 0; i < layout.tags.size(); ++i) {
    const TagPlacement& tag = layout.tags[i];
    const std::string at = where + ": tags[" + std::to_string(i) + "]";
    if (!(std::isfinite(tag.size) && tag.size > 0.0)) {
      throw HandEyeError(ErrorCode::InvalidLayout, "tag size " + number_text(tag.size) + " is not a positive length", at,
                         "give the edge of the tag's black square in metres (e.g. 0.06)");
    }
    if (!tag.T_pattern_tag.matrix().allFinite()) {
      throw HandEyeError(ErrorCode::NonFinite, "NaN or Inf in the tag's pose", at, "give finite x, y, z and quaternion");
    }
    if (!seen.insert(tag.id).second) {
      throw HandEyeError(ErrorCode::InvalidLayout, "tag id " + std::to_string(tag.id) + " appears twice", at,
                         "each tag of a pattern needs its own id");
    }
  }
}

}  // namespace handeye
