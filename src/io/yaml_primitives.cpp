// The readers and writers the file families share (yaml_primitives.h).
#include "yaml_primitives.h"

#include <Eigen/SVD>

#include "handeye_covariance/core/lie.h"
#include "handeye_covariance/core/validation.h"

namespace handeye {
namespace io {
namespace detail {

using Eigen::Isometry3d;
using Eigen::Matrix3d;
using Eigen::Vector3d;

// ---------------------------------------------------------------- reading

YAML::Node require(const YAML::Node& map, const std::string& key, const Location& at,
                   const std::string& hint) {
  if (!map.IsMap()) {
    throw HandEyeError(ErrorCode::MalformedFile, "expected a mapping with key `" + key + "`",
                       at.str(), hint);
  }
  const YAML::Node node = map[key];
  if (!node) throw HandEyeError(ErrorCode::MissingKey, "missing key `" + key + "`", at.str(), hint);
  return node;
}

double as_double(const YAML::Node& node, const Location& at) {
  try {
    if (!node.IsScalar()) throw YAML::BadConversion(node.Mark());
    return node.as<double>();
  } catch (const YAML::Exception&) {
    throw HandEyeError(ErrorCode::MalformedFile, "expected a number", at.str(),
                       "write a plain number (e.g. 0.125); NaN and Inf are refused");
  }
}

/// A number that must be finite: `message` and `fix` name NaN or Inf where it was found.
double as_finite(const YAML::Node& node, const Location& at, const std::string& message, const std::string& fix) {
  const double v = as_double(node, at);
  if (!std::isfinite(v)) throw HandEyeError(ErrorCode::NonFinite, message, at.str(), fix);
  return v;
}

/// A whole number in [lowest, highest], checked before it is converted (a double
/// beyond int's range, converted, is undefined behaviour: `id: 1e90`).
int as_integer(const YAML::Node& node, const Location& at, double lowest, double highest, const std::string& what) {
  const double v = as_double(node, at);
  if (!(v >= lowest && v <= highest) || v != std::floor(v)) {
    throw HandEyeError(ErrorCode::MalformedFile,
                       what + " must be a whole number from " + number_text(lowest, 10) + " to " + number_text(highest, 10) +
                           ", got " + number_text(v, 6),
                       at.str(), "write a plain integer, e.g. 0");
  }
  return static_cast<int>(v);
}

bool as_bool(const YAML::Node& node, const Location& at) {
  try {
    if (!node.IsScalar()) throw YAML::BadConversion(node.Mark());
    return node.as<bool>();
  } catch (const YAML::Exception&) {
    throw HandEyeError(ErrorCode::MalformedFile, "expected true or false", at.str(), "write true or false");
  }
}

std::string as_text(const YAML::Node& node, const Location& at) {
  if (!node.IsScalar()) {
    throw HandEyeError(ErrorCode::MalformedFile, "expected a name", at.str(), "write a plain name, e.g. base_link");
  }
  return node.Scalar();
}

/// A list of finite numbers of any length.
std::vector<double> as_number_list(const YAML::Node& node, const Location& at, const std::string& what) {
  if (!node.IsSequence()) {
    throw HandEyeError(ErrorCode::MalformedFile, "expected a list of numbers (" + what + ")", at.str(),
                       "write it as [a, b, ...]");
  }
  std::vector<double> values;
  for (std::size_t i = 0; i < node.size(); ++i) {
    values.push_back(as_finite(node[i], at[i], "NaN or Inf (" + what + ")", "fix the source that produced it"));
  }
  return values;
}

/// A 4x4 homogeneous matrix, row-major, as robot controllers and other tools
/// export poses. Rounded printouts are accepted up to the quaternion reader's
/// tolerance (|R^T R - I| <= 1e-3) and projected onto the nearest rotation
/// (SVD); anything further off, or a reflection, is refused.
Isometry3d read_pose_matrix(const YAML::Node& node, const Location& at) {
  const auto m = as_numbers<16>(node, at, "4x4 homogeneous matrix, row-major");
  if (m[12] != 0.0 || m[13] != 0.0 || m[14] != 0.0 || m[15] != 1.0) {
    throw HandEyeError(ErrorCode::MalformedFile, "the last row of a pose matrix must be 0 0 0 1", at.str(),
                       "give T (maps child to parent) as 16 numbers, row-major; check that it is not transposed");
  }
  Matrix3d R;
  R << m[0], m[1], m[2], m[4], m[5], m[6], m[8], m[9], m[10];
  const double orthonormality = (R.transpose() * R - Matrix3d::Identity()).norm();
  if (orthonormality > 1e-3 || R.determinant() <= 0.0) {
    throw HandEyeError(ErrorCode::RotationNotOrthonormal,
                       "the rotation block is not a rotation (|R^T R - I| = " + number_text(orthonormality, 4) +
                           ", det = " + number_text(R.determinant(), 4) + ")",
                       at.str(), "give a proper rotation (orthonormal, det +1) with enough digits; check the units and "
                                 "the row/column order");
  }
  const Eigen::JacobiSVD<Matrix3d> svd(R, Eigen::ComputeFullU | Eigen::ComputeFullV);
  return se3::make_pose(svd.matrixU() * svd.matrixV().transpose(), Vector3d(m[3], m[7], m[11]));
}

Isometry3d read_pose(const YAML::Node& node, const Location& at) {
  const std::string hint =
      "a pose is {translation: [x, y, z], rotation: [qx, qy, qz, qw]} or {matrix: [16 numbers, row-major]}";
  if (node.IsMap() && node["matrix"]) return read_pose_matrix(node["matrix"], at / "matrix");
  const auto t = as_numbers<3>(require(node, "translation", at, hint), at / "translation", "translation x, y, z in m");
  const auto q = as_numbers<4>(require(node, "rotation", at, hint), at / "rotation", "quaternion qx, qy, qz, qw");
  const Eigen::Quaterniond unit =
      checked_unit_quaternion(Eigen::Quaterniond(q[3], q[0], q[1], q[2]), (at / "rotation").str());
  return se3::make_pose(unit.toRotationMatrix(), Vector3d(t[0], t[1], t[2]));
}

/// A noise entry: {rotation: [9], translation: [9]} (no cross block) or the full
/// {pose: [36]} in ROS order (with the rotation-translation cross block).
PoseNoise read_covariance(const YAML::Node& node, const Location& at) {
  const std::string hint = "a noise entry is {rotation: [9 numbers, rad^2], translation: [9 numbers, m^2]}, row-major, "
                           "or {pose: [36 numbers, ROS order x y z rx ry rz]} with the cross block";
  PoseNoise c;
  if (node.IsMap() && node["pose"]) {
    if (node["rotation"] || node["translation"]) {
      throw HandEyeError(ErrorCode::MalformedFile, "both `pose` and `rotation`/`translation` are given", at.str(),
                         "give either the full `pose` 6x6 or the two 3x3 blocks, not both");
    }
    const Matrix6d full = from_row_major_6x6(as_numbers<36>(node["pose"], at / "pose", "6x6 covariance, ROS order"));
    check_covariance(full, (at / "pose").str());
    c = PoseNoise::from_pose_covariance(full);
  } else {
    c.rotation = from_row_major_3x3(as_numbers<9>(require(node, "rotation", at, hint), at / "rotation", "3x3 covariance, rad^2"));
    c.translation = from_row_major_3x3(as_numbers<9>(require(node, "translation", at, hint), at / "translation", "3x3 covariance, m^2"));
  }
  check_covariance(c, at.str());
  return c;
}

/// `noise: {robot_key: {...}, camera_key: {...}}` (effector/pattern or A/B).
MeasurementNoise read_noise(const YAML::Node& node, const Location& at, const char* robot_key,
                            const char* camera_key) {
  const std::string hint = std::string("noise is {") + robot_key + ": {rotation, translation}, " +
                           camera_key + ": {rotation, translation}}";
  MeasurementNoise noise;
  noise.robot = read_covariance(require(node, robot_key, at, hint), at / robot_key);
  noise.camera = read_covariance(require(node, camera_key, at, hint), at / camera_key);
  return noise;
}

std::optional<MeasurementNoise> optional_noise(const YAML::Node& map, const Location& at,
                                               const char* robot_key, const char* camera_key) {
  const YAML::Node node = map["noise"];
  if (!node || node.IsNull()) return std::nullopt;
  return read_noise(node, at / "noise", robot_key, camera_key);
}

Setup read_setup(const YAML::Node& node, const Location& at) {
  return setup_from_string(node.IsScalar() ? node.Scalar() : "", at.str());
}

YAML::Node load(const std::string& text, const std::string& source) {
  try {
    YAML::Node root = YAML::Load(text);
    if (!root.IsMap()) {
      throw HandEyeError(ErrorCode::MalformedFile, "the file is not a YAML mapping", source,
                         "see docs/file_formats.md for the format");
    }
    return root;
  } catch (const YAML::ParserException& e) {
    throw HandEyeError(ErrorCode::MalformedFile, std::string("YAML syntax error: ") + e.msg,
                       source + ":" + std::to_string(e.mark.line + 1) + ":" + std::to_string(e.mark.column + 1),
                       "fix the YAML syntax at that line");
  }
}

YAML::Node require_list(const YAML::Node& root, const std::string& key, const Location& at) {
  const YAML::Node list = require(root, key, at, "the file needs a `" + key + ":` list");
  if (!list.IsSequence()) {
    throw HandEyeError(ErrorCode::MalformedFile, "`" + key + "` must be a list", (at / key).str(),
                       "write `" + key + ":` followed by `- ...` entries");
  }
  return list;
}

// ---------------------------------------------------------------- writing

void emit_numbers(YAML::Emitter& out, const double* values, std::size_t n) {
  out << YAML::Flow << YAML::BeginSeq;
  for (std::size_t i = 0; i < n; ++i) out << values[i];
  out << YAML::EndSeq;
}

void emit_pose(YAML::Emitter& out, const Isometry3d& pose) {
  const Vector3d t = pose.translation();
  Eigen::Quaterniond q(pose.linear());
  if (q.w() < 0) q.coeffs() *= -1.0;  // one canonical sign, w >= 0
  const double quaternion[4] = {q.x(), q.y(), q.z(), q.w()};
  out << YAML::Key << "translation" << YAML::Value;
  emit_numbers(out, t.data(), 3);
  out << YAML::Key << "rotation" << YAML::Value;
  emit_numbers(out, quaternion, 4);
}

/// `key: {translation: [...], rotation: [...]}` on one line.
void emit_keyed_pose(YAML::Emitter& out, const char* key, const Isometry3d& pose) {
  out << YAML::Key << key << YAML::Value << YAML::Flow << YAML::BeginMap;
  emit_pose(out, pose);
  out << YAML::EndMap;
}

void emit_covariance3(YAML::Emitter& out, const Matrix3d& covariance) {
  const auto values = to_row_major_3x3(covariance);
  emit_numbers(out, values.data(), values.size());
}

/// The two blocks when there is no cross block (readable), else the full 6x6.
void emit_pose_noise(YAML::Emitter& out, const PoseNoise& c) {
  out << YAML::BeginMap;
  if (c.has_cross_block()) {
    out << YAML::Key << "pose" << YAML::Value;
    const auto values = to_row_major_6x6(c.as_pose_covariance());
    emit_numbers(out, values.data(), values.size());
  } else {
    out << YAML::Key << "rotation" << YAML::Value;
    emit_covariance3(out, c.rotation);
    out << YAML::Key << "translation" << YAML::Value;
    emit_covariance3(out, c.translation);
  }
  out << YAML::EndMap;
}

void emit_noise(YAML::Emitter& out, const MeasurementNoise& noise, const char* robot_key,
                const char* camera_key) {
  out << YAML::BeginMap;
  out << YAML::Key << robot_key << YAML::Value;
  emit_pose_noise(out, noise.robot);
  out << YAML::Key << camera_key << YAML::Value;
  emit_pose_noise(out, noise.camera);
  out << YAML::EndMap;
}

YAML::Emitter& new_emitter(YAML::Emitter& out) {
  out.SetDoublePrecision(17);  // round-trips every double exactly
  return out;
}

}  // namespace detail
}  // namespace io
}  // namespace handeye
