// The readers and writers every file family shares (samples_file.cpp,
// result_file.cpp, pose_files.cpp, target_file.cpp, files.cpp). Internal to io:
// not installed, so yaml-cpp stays out of the public headers.
#pragma once

#include <yaml-cpp/yaml.h>

#include <Eigen/Geometry>

#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/core/measurements.h"
#include "handeye_covariance/core/pose_covariance.h"
#include "handeye_covariance/core/rig.h"

namespace handeye {
namespace io {
namespace detail {

// ---------------------------------------------------------------- reading

/// Where we are in a file, for messages: "samples.yaml: samples[3].pattern.rotation".
struct Location {
  std::string source;
  std::string path;
  Location operator/(const std::string& key) const {
    return {source, path.empty() ? key : path + "." + key};
  }
  Location operator[](std::size_t index) const {
    return {source, path + "[" + std::to_string(index) + "]"};
  }
  std::string str() const { return source + ": " + (path.empty() ? "top level" : path); }
};

/// `map[key]`; MissingKey (or MalformedFile when `map` is not a map) with `hint` as the fix.
YAML::Node require(const YAML::Node& map, const std::string& key, const Location& at, const std::string& hint);
double as_double(const YAML::Node& node, const Location& at);
/// A number that must be finite: `message` and `fix` name NaN or Inf where it was found.
double as_finite(const YAML::Node& node, const Location& at, const std::string& message, const std::string& fix);
/// A whole number in [lowest, highest], checked before it is converted (a double
/// beyond int's range, converted, is undefined behaviour: `id: 1e90`).
int as_integer(const YAML::Node& node, const Location& at, double lowest, double highest, const std::string& what);
bool as_bool(const YAML::Node& node, const Location& at);
std::string as_text(const YAML::Node& node, const Location& at);

/// Exactly N finite numbers; `what` says what they are in the message.
template <std::size_t N>
std::array<double, N> as_numbers(const YAML::Node& node, const Location& at, const std::string& what) {
  if (!node.IsSequence()) {
    throw HandEyeError(ErrorCode::MalformedFile, "expected a list of " + std::to_string(N) + " numbers (" + what + ")",
                       at.str(), "write it as [a, b, ...]");
  }
  if (node.size() != N) {
    throw HandEyeError(ErrorCode::WrongLength,
                       "expected " + std::to_string(N) + " numbers (" + what + "), got " +
                           std::to_string(node.size()),
                       at.str(), "give exactly " + std::to_string(N) + " numbers");
  }
  std::array<double, N> values;
  for (std::size_t i = 0; i < N; ++i) {
    values[i] = as_finite(node[i], at[i], "NaN or Inf (" + what + ")", "drop this entry or fix the source that produced it");
  }
  return values;
}
/// A list of finite numbers of any length.
std::vector<double> as_number_list(const YAML::Node& node, const Location& at, const std::string& what);
/// A 4x4 homogeneous matrix, row-major, projected onto the nearest rotation (within 1e-3).
Eigen::Isometry3d read_pose_matrix(const YAML::Node& node, const Location& at);
/// {translation: [x, y, z], rotation: [qx, qy, qz, qw]} or {matrix: [16 numbers]}.
Eigen::Isometry3d read_pose(const YAML::Node& node, const Location& at);
/// A noise entry: {rotation: [9], translation: [9]} or {pose: [36]} (ROS order).
PoseNoise read_covariance(const YAML::Node& node, const Location& at);
/// `noise: {robot_key: {...}, camera_key: {...}}` (effector/pattern or A/B).
MeasurementNoise read_noise(const YAML::Node& node, const Location& at, const char* robot_key, const char* camera_key);
/// The `noise` key of `map`, when it is there and not null.
std::optional<MeasurementNoise> optional_noise(const YAML::Node& map, const Location& at, const char* robot_key,
                                               const char* camera_key);
Setup read_setup(const YAML::Node& node, const Location& at);
/// The text as a YAML mapping; a syntax error names the line and column.
YAML::Node load(const std::string& text, const std::string& source);
/// `root[key]`, which must be a list.
YAML::Node require_list(const YAML::Node& root, const std::string& key, const Location& at);

// ---------------------------------------------------------------- writing

/// `[a, b, ...]` on one line.
void emit_numbers(YAML::Emitter& out, const double* values, std::size_t n);
/// `translation` and `rotation` keys (quaternion with w >= 0) into the open map.
void emit_pose(YAML::Emitter& out, const Eigen::Isometry3d& pose);
/// `key: {translation: [...], rotation: [...]}` on one line.
void emit_keyed_pose(YAML::Emitter& out, const char* key, const Eigen::Isometry3d& pose);
void emit_covariance3(YAML::Emitter& out, const Eigen::Matrix3d& covariance);
/// The two blocks when there is no cross block (readable), else the full 6x6.
void emit_pose_noise(YAML::Emitter& out, const PoseNoise& c);
void emit_noise(YAML::Emitter& out, const MeasurementNoise& noise, const char* robot_key, const char* camera_key);
/// `out` set to write every double so that it reads back exactly.
YAML::Emitter& new_emitter(YAML::Emitter& out);

}  // namespace detail
}  // namespace io
}  // namespace handeye
