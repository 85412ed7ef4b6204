#include "handeye_covariance/core/target.h"

#include <cstdio>
#include <stdexcept>

#include "handeye_covariance/core/rig.h"
#include "handeye_covariance/core/units.h"

namespace handeye {

const TargetKind& Target::kind() const {
  if (!kind_) throw std::logic_error("a Target with no kind was used (default-constructed and never assigned)");
  return *kind_;
}

std::string Target::describe() const { return kind().describe(*this); }

std::string Target::kind_name() const { return kind().name(); }

const TargetKind* find_target_kind(const std::string& name) {
  for (const TargetKind* kind : target_kinds()) {
    if (kind->name() == name) return kind;
  }
  return nullptr;
}

const TargetKind* find_target_kind_of_type(const std::string& type) {
  for (const TargetKind* kind : target_kinds()) {
    for (const std::string& t : kind->file_types()) {
      if (t == type) return kind;
    }
  }
  return nullptr;
}

std::string one_of(const std::vector<std::string>& names) {
  std::string text;
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (i > 0) text += i + 1 == names.size() ? " or " : ", ";
    text += names[i];
  }
  return text;
}

std::string target_kind_names() {
  std::vector<std::string> names;
  for (const TargetKind* kind : target_kinds()) names.push_back(kind->name());
  return one_of(names);
}

std::string target_file_types() {
  std::vector<std::string> types;
  for (const TargetKind* kind : target_kinds()) {
    for (const std::string& t : kind->file_types()) types.push_back(t);
  }
  return one_of(types);
}

std::string millimetres_text(double metres, int decimals) {
  char text[32];
  std::snprintf(text, sizeof text, "%.*f mm", decimals, millimetres(metres));
  return text;
}

Eigen::Matrix3d opencv_board_to_face() { return Eigen::Vector3d(1.0, -1.0, -1.0).asDiagonal(); }

Eigen::Isometry3d target_face(const Target& target) { return target.kind().face(target); }

bool is_half_turn_symmetric(const Target& target) { return target.kind().half_turn_symmetric(target); }

Eigen::Isometry3d face_half_turn(const Target& target) {
  Rig rig;
  rig.T_pattern_face = target_face(target);
  return rig.face_half_turn();
}

void set_target(Rig& rig, const Target& target) {
  rig.T_pattern_face = target_face(target);
  rig.face_size = target_face_size(target);
  rig.symmetric_face = is_half_turn_symmetric(target);
}

Eigen::Isometry3d half_turn(const Target& target) {
  return is_half_turn_symmetric(target) ? face_half_turn(target) : Eigen::Isometry3d::Identity();
}

Eigen::Vector2d target_face_size(const Target& target) { return target.kind().face_size(target); }

}  // namespace handeye
