// The marker kinds, ArUco and AprilTag (core/targets/markers.h): one class, as
// both are a TagLayout told apart by its family.
#include "handeye_covariance/core/targets/markers.h"

#include <cctype>
#include <cmath>
#include <set>

#include "handeye_covariance/core/lie.h"

namespace handeye {
namespace {

const TagLayout& layout(const Target& target) { return target.as<TagLayout>(); }

class MarkersKind : public TargetKind {
 public:
  explicit MarkersKind(bool aruco) : aruco_(aruco) {}

  std::string name() const override { return aruco_ ? "aruco" : "apriltag"; }
  std::vector<std::string> file_types() const override {
    return aruco_ ? std::vector<std::string>{"aruco", "aruco_board"} : std::vector<std::string>{"apriltag"};
  }
  std::string example(const std::string& type) const override {
    if (type == "aruco_board") {
      return "e.g. {type: aruco_board, dictionary: DICT_4X4_50, markers: [4, 3], marker: 0.06, separation: 0.015}";
    }
    return aruco_ ? "e.g. {type: aruco, dictionary: DICT_4X4_50, id: 7, marker: 0.05}"
                  : "e.g. {type: apriltag, family: tag36h11, id: 10, size: 0.048}";
  }
  // make_target(layout): the family, not the type, names the detector.
  Target parse(const std::string& type, const TargetFields& fields) const override {
    const auto id = [&](const char* key) { return fields.integer(key, 0, 1e6, "the marker id"); };
    if (type == "aruco") {
      const std::string dictionary = fields.text("dictionary");
      return make_target(single_tag_layout(id("id"), fields.length("marker"), dictionary));
    }
    if (type == "aruco_board") {
      const std::string dictionary = fields.text("dictionary");
      const auto markers = fields.pair("markers", "markers");
      const double separation = fields.number("separation");
      if (!(separation >= 0.0 && separation < 10.0)) fields.refuse("separation", "`separation` must be a length in m, 0 or more");
      const int first = fields.has("first_id") ? fields.integer("first_id", 0, 1e6, "the first id") : 0;
      return make_target(aruco_grid_layout(dictionary, markers[0], markers[1], fields.length("marker"), separation, first));
    }
    const std::string family = fields.has("family") ? fields.text("family") : "tag36h11";
    return make_target(single_tag_layout(id("id"), fields.length("size"), family));
  }
  std::vector<std::string> length_keys() const override {
    return aruco_ ? std::vector<std::string>{"marker", "separation"} : std::vector<std::string>{"size"};
  }

  std::string describe(const Target& target) const override {
    const TagLayout& markers = layout(target);
    const std::string what = aruco_ ? "ArUco" : "AprilTag";
    if (markers.tags.size() == 1) {
      return what + " " + markers.family + " id " + std::to_string(markers.tags[0].id) + ", " +
             millimetres_text(markers.tags[0].size);
    }
    return what + " board of " + std::to_string(markers.tags.size()) + " " + markers.family + " markers";
  }
  std::string sizes_text(const Target& target) const override {
    const TagLayout& markers = layout(target);
    std::set<double> sizes;
    for (const TagPlacement& tag : markers.tags) sizes.insert(tag.size);
    std::string text = markers.family + " ids";
    for (int id : markers.ids()) text += " " + std::to_string(id);
    text += ", black square";
    for (double s : sizes) text += " " + millimetres_text(s, 3);
    return text;
  }
  std::string frame_text(const Target& target) const override {
    return layout(target).tags.size() == 1
               ? "frame: origin at the marker's centre, x right, y up, z out of the paper"
               : "frame: the layout's (each marker's x right, y up, z out of the paper; the first marker upright)";
  }
  std::string ruler_name() const override { return "marker (black square)"; }
  double ruler_length(const Target& target) const override {
    return layout(target).tags.empty() ? 0.0 : layout(target).tags.front().size;
  }

  Eigen::Isometry3d face(const Target& target) const override {
    const TagLayout& markers = layout(target);
    if (markers.tags.empty()) return Eigen::Isometry3d::Identity();
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    for (const TagPlacement& tag : markers.tags) centre += tag.T_pattern_tag.translation();
    centre /= static_cast<double>(markers.tags.size());
    return se3::make_pose(markers.tags.front().T_pattern_tag.linear(), centre);
  }
  Eigen::Vector2d face_size(const Target& target) const override {
    // The markers' corners in the face's frame: their extent along its x and y.
    const TagLayout& markers = layout(target);
    const Eigen::Isometry3d face_inverse = face(target).inverse();
    Eigen::Vector2d low = Eigen::Vector2d::Constant(INFINITY), high = -low;
    for (const TagPlacement& tag : markers.tags) {
      for (const Eigen::Vector3d& corner : tag.corners()) {
        const Eigen::Vector2d p = (face_inverse * corner).head<2>();
        low = low.cwiseMin(p), high = high.cwiseMax(p);
      }
    }
    return markers.tags.empty() ? Eigen::Vector2d::Zero() : Eigen::Vector2d(high - low);
  }

 private:
  bool aruco_;
};

}  // namespace

const TargetKind& aruco_kind() {
  static const MarkersKind kind(true);
  return kind;
}

const TargetKind& apriltag_kind() {
  static const MarkersKind kind(false);
  return kind;
}

Target make_target(const TagLayout& markers) {
  return Target(names_aruco_dictionary(markers.family) ? aruco_kind() : apriltag_kind(), markers);
}

bool names_aruco_dictionary(const std::string& name) {
  if (name.size() < 4) return false;
  std::string head = name.substr(0, 4);
  for (char& c : head) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return head == "DICT";
}

TagLayout aruco_grid_layout(const std::string& name, int columns, int rows, double marker, double separation,
                            int first_id) {
  TagLayout layout;
  layout.family = name;
  const Eigen::Matrix3d flip = opencv_board_to_face();  // each marker in the board's frame
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < columns; ++c) {
      TagPlacement tag;
      tag.id = first_id + r * columns + c;
      tag.size = marker;
      tag.T_pattern_tag = se3::make_pose(flip, Eigen::Vector3d(c * (marker + separation) + 0.5 * marker,
                                                               r * (marker + separation) + 0.5 * marker, 0.0));
      layout.tags.push_back(tag);
    }
  }
  return layout;
}

}  // namespace handeye
