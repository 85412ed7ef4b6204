// The ChArUco kind (core/targets/charuco.h).
#include "handeye_covariance/core/targets/charuco.h"

#include "handeye_covariance/core/lie.h"

namespace handeye {
namespace {

const CharucoTarget& charuco_of(const Target& target) { return target.as<CharucoTarget>(); }

class CharucoKind : public TargetKind {
 public:
  std::string name() const override { return "charuco"; }
  std::vector<std::string> file_types() const override { return {"charuco"}; }
  std::string example(const std::string&) const override {
    return "e.g. {type: charuco, squares: [7, 5], square: 0.036, marker: 0.018, dictionary: DICT_6X6_250}";
  }
  Target parse(const std::string&, const TargetFields& fields) const override {
    const auto squares = fields.pair("squares", "squares");
    return make_target(CharucoTarget{squares[0], squares[1], fields.length("square"), fields.length("marker"),
                                     fields.text("dictionary")});
  }
  std::vector<std::string> length_keys() const override { return {"square", "marker"}; }

  std::string describe(const Target& target) const override {
    const CharucoTarget& t = charuco_of(target);
    return "ChArUco " + std::to_string(t.columns) + " x " + std::to_string(t.rows) + " squares of " +
           millimetres_text(t.square) + ", " + millimetres_text(t.marker) + " markers, " + t.dictionary;
  }
  std::string sizes_text(const Target& target) const override {
    const CharucoTarget& t = charuco_of(target);
    return "square " + millimetres_text(t.square, 3) + ", marker " + millimetres_text(t.marker, 3) + " (black border included), " +
           t.dictionary;
  }
  std::string frame_text(const Target&) const override {
    return "frame (OpenCV's): origin at the board's top-left corner, x along a row (right), y down, z into the board";
  }
  std::string ruler_name() const override { return "square"; }
  double ruler_length(const Target& target) const override { return charuco_of(target).square; }

  Eigen::Isometry3d face(const Target& target) const override {
    const CharucoTarget& t = charuco_of(target);
    return se3::make_pose(opencv_board_to_face(), Eigen::Vector3d(0.5 * t.columns * t.square, 0.5 * t.rows * t.square, 0.0));
  }
  Eigen::Vector2d face_size(const Target& target) const override {
    const CharucoTarget& t = charuco_of(target);
    return Eigen::Vector2d(t.columns - 2, t.rows - 2) * t.square;
  }
};

}  // namespace

const TargetKind& charuco_kind() {
  static const CharucoKind kind;
  return kind;
}

Target make_target(const CharucoTarget& charuco) { return Target(charuco_kind(), charuco); }

}  // namespace handeye
