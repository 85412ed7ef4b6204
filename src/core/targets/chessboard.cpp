// The chessboard kind (core/targets/chessboard.h).
#include "handeye_covariance/core/targets/chessboard.h"

#include "handeye_covariance/core/lie.h"

namespace handeye {
namespace {

const ChessboardTarget& chessboard_of(const Target& target) { return target.as<ChessboardTarget>(); }

class ChessboardKind : public TargetKind {
 public:
  std::string name() const override { return "chessboard"; }
  std::vector<std::string> file_types() const override { return {"chessboard"}; }
  std::string example(const std::string&) const override {
    return "e.g. {type: chessboard, inner_corners: [9, 6], square: 0.0236}";
  }
  Target parse(const std::string&, const TargetFields& fields) const override {
    const auto corners = fields.pair("inner_corners", "inner corners");
    return make_target(ChessboardTarget{corners[0], corners[1], fields.length("square")});
  }
  std::vector<std::string> length_keys() const override { return {"square"}; }

  std::string describe(const Target& target) const override {
    const ChessboardTarget& t = chessboard_of(target);
    return "chessboard " + std::to_string(t.columns) + " x " + std::to_string(t.rows) + " inner corners, " +
           millimetres_text(t.square) + " squares";
  }
  std::string sizes_text(const Target& target) const override { return "square " + millimetres_text(chessboard_of(target).square, 3); }
  std::string frame_text(const Target&) const override {
    return "frame (OpenCV's): origin at the top-left inner corner, x along a row (right), y down, z into the board";
  }
  std::string ruler_name() const override { return "square"; }
  double ruler_length(const Target& target) const override { return chessboard_of(target).square; }

  Eigen::Isometry3d face(const Target& target) const override {
    const ChessboardTarget& t = chessboard_of(target);
    return se3::make_pose(opencv_board_to_face(),
                          Eigen::Vector3d(0.5 * (t.columns - 1) * t.square, 0.5 * (t.rows - 1) * t.square, 0.0));
  }
  Eigen::Vector2d face_size(const Target& target) const override {
    const ChessboardTarget& t = chessboard_of(target);
    return Eigen::Vector2d(t.columns - 1, t.rows - 1) * t.square;
  }
  bool half_turn_symmetric(const Target& target) const override {
    return (chessboard_of(target).columns + chessboard_of(target).rows) % 2 == 0;
  }
};

}  // namespace

const TargetKind& chessboard_kind() {
  static const ChessboardKind kind;
  return kind;
}

Target make_target(const ChessboardTarget& chessboard) { return Target(chessboard_kind(), chessboard); }

}  // namespace handeye
