// A calibration target as printed (no ROS, no OpenCV): its kind and the kind's
// own parameters. A kind is a TargetKind (its file keys, description, frame and
// symmetry), one file per kind in core/targets/, listed once in
// src/core/target_kinds.cpp. The other layers hold their part of a kind in a
// table keyed by the kind's name: the detector (vision/target.h), the
// renderer's drawing (simulation/pattern_renderer.h), the printer's
// (print/target_printer.h). docs/targets.md, "Adding a target kind".
//
// Frames: each kind's own (core/targets/*.h); a face frame (target_face) is
// common to all.
#pragma once

#include <Eigen/Geometry>
#include <any>
#include <array>
#include <string>
#include <vector>

#include "handeye_covariance/core/tag_layout.h"

namespace handeye {

class TargetKind;

class Target {
 public:
  /// No kind: a placeholder to assign to (kind() throws).
  Target() = default;
  Target(const TargetKind& kind, std::any parameters) : kind_(&kind), parameters_(std::move(parameters)) {}

  const TargetKind& kind() const;
  /// The kind's parameters (ChessboardTarget, CharucoTarget, TagLayout, ...);
  /// as<>() throws std::bad_any_cast for another type, get<>() gives nullptr.
  template <class Parameters>
  const Parameters& as() const {
    return std::any_cast<const Parameters&>(parameters_);
  }
  template <class Parameters>
  const Parameters* get() const {
    return std::any_cast<Parameters>(&parameters_);
  }

  /// e.g. "chessboard 9 x 6 inner corners, 23.6 mm squares".
  std::string describe() const;
  /// The kind's name: "chessboard", "charuco", "aruco" (one marker or a board),
  /// "apriltag"; the node's `target` argument.
  std::string kind_name() const;

 private:
  const TargetKind* kind_ = nullptr;
  std::any parameters_;
};

/// A target file's keys as a kind reads them. io implements it on yaml-cpp (the
/// core reads no YAML); each throws HandEyeError naming the file and the key,
/// with the kind's example (TargetKind::example) as the fix.
class TargetFields {
 public:
  virtual ~TargetFields() = default;
  virtual bool has(const std::string& key) const = 0;
  virtual std::string text(const std::string& key) const = 0;
  virtual double number(const std::string& key) const = 0;
  /// A length in m, above 0 and below 10.
  virtual double length(const std::string& key) const = 0;
  virtual int integer(const std::string& key, double lowest, double highest, const std::string& what) const = 0;
  /// [columns, rows], each 1 to 1000 (`what`: "inner corners", "squares").
  virtual std::array<int, 2> pair(const std::string& key, const std::string& what) const = 0;
  /// Refuses the key's value: HandEyeError(InvalidLayout).
  [[noreturn]] virtual void refuse(const std::string& key, const std::string& message) const = 0;
};

/// One kind of target: everything about it that needs no image library.
class TargetKind {
 public:
  virtual ~TargetKind() = default;
  /// "chessboard": the node's ~target, and every layer's key for the kind.
  virtual std::string name() const = 0;

  /// The `type:` values of a target file that are this kind ("aruco", "aruco_board").
  virtual std::vector<std::string> file_types() const = 0;
  /// A file of that type, for messages: "{type: chessboard, inner_corners: [9, 6], square: 0.0236}".
  virtual std::string example(const std::string& type) const = 0;
  virtual Target parse(const std::string& type, const TargetFields& fields) const = 0;
  /// The file's keys that hold lengths in m (`handeye target --measured-square` scales them).
  virtual std::vector<std::string> length_keys() const = 0;

  virtual std::string describe(const Target& target) const = 0;
  /// Its sizes and codes as printed beside it: "square 20.000 mm".
  virtual std::string sizes_text(const Target& target) const = 0;
  /// The frame its detector reports, in words (printed beside it).
  virtual std::string frame_text(const Target& target) const = 0;
  /// What a ruler measures on the print ("square", "marker (black square)") and its length.
  virtual std::string ruler_name() const = 0;
  virtual double ruler_length(const Target& target) const = 0;

  /// T_pattern_face (target_face).
  virtual Eigen::Isometry3d face(const Target& target) const = 0;
  /// The detected points' extent about the face (target_face_size).
  virtual Eigen::Vector2d face_size(const Target& target) const = 0;
  /// is_half_turn_symmetric.
  virtual bool half_turn_symmetric(const Target&) const { return false; }
};

/// Every kind, in the order of src/core/target_kinds.cpp (the one list).
const std::vector<const TargetKind*>& target_kinds();
/// The kind of that name, or nullptr.
const TargetKind* find_target_kind(const std::string& name);

/// A layer's part of a kind, from the layer's one table (`entries`, each with a `name`:
/// the kind's). Throws HandEyeError(InvalidLayout): "the target kind `name` has no
/// `missing`", and where to list it (`entry_type` in `table_file`).
[[noreturn]] void throw_no_layer_entry(const std::string& name, const std::string& missing, const std::string& layer,
                                       const std::string& entry_type, const std::string& table_file);
template <class Entry>
const Entry& layer_entry(const std::vector<Entry>& entries, const std::string& name, const std::string& missing,
                         const std::string& layer, const std::string& entry_type, const std::string& table_file) {
  for (const Entry& entry : entries) {
    if (entry.name == name) return entry;
  }
  throw_no_layer_entry(name, missing, layer, entry_type, table_file);
}
/// The kind whose files have `type: type`, or nullptr.
const TargetKind* find_target_kind_of_type(const std::string& type);
/// "chessboard, charuco, aruco or apriltag", from the list.
std::string target_kind_names();
/// "chessboard, charuco, aruco, aruco_board or apriltag", from the list.
std::string target_file_types();
/// "a, b or c".
std::string one_of(const std::vector<std::string>& names);

/// "23.6 mm".
std::string millimetres_text(double metres, int decimals = 1);

/// OpenCV's board frames (y down, z into the board) seen as a printed face or a
/// marker's frame (y up, z out of it): the same plane turned by 180 degrees about x.
Eigen::Matrix3d opencv_board_to_face();

/// T_pattern_face: a frame at the middle of the target's printed face, x right,
/// y up, z out of the face towards a camera that sees it (the frame random_view
/// looks at; OpenCV's board frames have y down and z into the board). Markers:
/// the centroid of their centres, turned as the first marker.
Eigen::Isometry3d target_face(const Target& target);

/// The target looks the same turned by 180 degrees about its face's normal through
/// the face's centre: a chessboard whose inner-corner counts columns + rows are
/// even (both odd or both even, e.g. 9 x 7 or 8 x 6), whose squares' colours the
/// turn maps onto themselves. Its detected pose is then one of two candidates, P and
/// P * half_turn(target), told apart only by the robot's motion
/// (estimation/symmetric_views.h). ChArUco, ArUco and AprilTag boards are not: the
/// turn moves each marker to where another id (or none) is printed, so the
/// markers' ids tell the turn apart.
bool is_half_turn_symmetric(const Target& target);

/// F = T_pattern_pattern': the pose of the pattern frame turned by pi about the
/// face's normal through the face's centre (target_face) in the original frame, so
/// the other candidate of a detected T_camera_pattern P is P * F (F = F^-1). For
/// OpenCV's chessboard frame: the turn about z through ((columns - 1) s / 2,
/// (rows - 1) s / 2, 0). The identity when the target is not symmetric
/// (is_half_turn_symmetric): its pose has one candidate.
Eigen::Isometry3d half_turn(const Target& target);

/// The same turn about the face whatever the target (a tag, a ChArUco board): what
/// half_turn gives for a symmetric one. For tests that plant the ambiguity on
/// sessions of targets that do not have it.
Eigen::Isometry3d face_half_turn(const Target& target);

struct Rig;
/// What a session's geometry takes from its target: where its face is
/// (Rig::T_pattern_face, target_face), its size (Rig::face_size,
/// target_face_size) and whether it looks the same turned by 180 degrees
/// (Rig::symmetric_face, is_half_turn_symmetric).
void set_target(Rig& rig, const Target& target);

/// The width and height (m) of the target's detected points about target_face:
/// a chessboard's and a ChArUco board's inner corners, the markers' corners.
Eigen::Vector2d target_face_size(const Target& target);

}  // namespace handeye

