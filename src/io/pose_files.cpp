// Robot pose files in every format and the CSV pose table (pose_files.h).
#include "handeye_covariance/io/pose_files.h"

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <optional>
#include <sstream>

#include "handeye_covariance/core/lie.h"
#include "handeye_covariance/core/validation.h"
#include "handeye_covariance/io/files.h"
#include "yaml_primitives.h"

namespace handeye {
namespace io {

using namespace detail;  // the shared readers and writers (yaml_primitives.h)
using Eigen::Isometry3d;
using Eigen::Matrix3d;
using Eigen::Vector3d;

// ---------------------------------------------------------------- robot poses

namespace {

/// Numbers separated by white space, commas or semicolons; nullopt when the text
/// holds anything else (so it is not a plain-text matrix).
std::optional<std::vector<double>> plain_numbers(const std::string& text) {
  std::string spaced = text;
  for (char& c : spaced) {
    if (c == ',' || c == ';') c = ' ';
  }
  std::istringstream in(spaced);
  std::vector<double> values;
  std::string word;
  while (in >> word) {
    char* end = nullptr;
    const double v = std::strtod(word.c_str(), &end);
    if (end == word.c_str() || *end != '\0') return std::nullopt;
    values.push_back(v);
  }
  return values;
}

}  // namespace

Eigen::Isometry3d parse_robot_pose(const std::string& text, const std::string& source) {
  const Location at{source, ""};
  const std::string hint =
      "a robot pose file holds T_base_effector (m) as {matrix: [16 numbers, row-major]}, {translation: [x, y, z], "
      "rotation: [qx, qy, qz, qw]}, ViSP's {data: [[tx], [ty], [tz], [tux], [tuy], [tuz]]} or 16 plain numbers";
  if (const auto numbers = plain_numbers(text); numbers && !numbers->empty()) {
    if (numbers->size() != 16) {
      throw HandEyeError(ErrorCode::WrongLength,
                         "a plain-text pose needs 16 numbers (a 4x4 matrix), got " + std::to_string(numbers->size()),
                         at.str(), hint);
    }
    YAML::Node list(YAML::NodeType::Sequence);
    for (double v : *numbers) list.push_back(v);
    return read_pose_matrix(list, at);
  }
  const YAML::Node root = load(text, source);
  if (root.IsMap() && root["data"]) {  // ViSP's vpPoseVector: 6 rows of one number
    const YAML::Node data = root["data"];
    const Location where = at / "data";
    if (!data.IsSequence() || data.size() != 6) {
      throw HandEyeError(data.IsSequence() ? ErrorCode::WrongLength : ErrorCode::MalformedFile,
                         "ViSP's pose vector needs 6 rows [tx], [ty], [tz], [tux], [tuy], [tuz]", where.str(), hint);
    }
    Vector6d v;
    for (std::size_t i = 0; i < 6; ++i) {
      const YAML::Node row = data[i];
      v[static_cast<Eigen::Index>(i)] = row.IsSequence() ? as_numbers<1>(row, where[i], "one number")[0]
                                                          : as_finite(row, where[i], "NaN or Inf in the pose vector", hint);
    }
    return se3::make_pose(so3::exp(v.tail<3>()), v.head<3>());
  }
  if (!root.IsMap()) throw HandEyeError(ErrorCode::MalformedFile, "not a pose", at.str(), hint);
  return read_pose(root, at);
}

Eigen::Isometry3d read_robot_pose(const std::string& path) { return parse_robot_pose(read_file(path), path); }

std::vector<PoseTableRow> parse_pose_table(const std::string& text, const std::string& source) {
  std::vector<PoseTableRow> rows;
  std::stringstream in(text);
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    std::stringstream fields(line);
    std::vector<std::string> cells;
    for (std::string cell; std::getline(fields, cell, ',');) cells.push_back(cell);
    const std::string where = source + " line " + std::to_string(number);
    double v[7];
    bool numeric = cells.size() == 8;
    for (int i = 0; numeric && i < 7; ++i) {
      char* end = nullptr;
      const char* cell = cells[static_cast<std::size_t>(i + 1)].c_str();
      v[i] = std::strtod(cell, &end);
      while (end != cell && std::isspace(static_cast<unsigned char>(*end))) ++end;
      numeric = end != cell && *end == '\0' && std::isfinite(v[i]);  // the whole cell is one number
    }
    if (!numeric) {
      if (number == 1) continue;  // a header
      throw HandEyeError(ErrorCode::MalformedFile, "expected image,tx,ty,tz,qx,qy,qz,qw", where,
                         "one line per image: its file name, the translation (m) and the unit quaternion");
    }
    const Eigen::Quaterniond q = checked_unit_quaternion(Eigen::Quaterniond(v[6], v[3], v[4], v[5]), where);
    const std::string name = cells[0].substr(0, cells[0].find_last_not_of(" \t\r") + 1);
    rows.push_back({name, se3::make_pose(q.toRotationMatrix(), Eigen::Vector3d(v[0], v[1], v[2])), where});
  }
  return rows;
}

}  // namespace io
}  // namespace handeye
