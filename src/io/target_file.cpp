// Target files, tag layouts and ROS camera_info (target_file.h).
#include "handeye_covariance/io/target_file.h"

#include <array>

#include "handeye_covariance/core/lie.h"
#include "handeye_covariance/core/targets/markers.h"
#include "handeye_covariance/core/validation.h"
#include "handeye_covariance/io/files.h"
#include "yaml_primitives.h"

namespace handeye {
namespace io {

using namespace detail;  // the shared readers and writers (yaml_primitives.h)
using Eigen::Isometry3d;
using Eigen::Matrix3d;
using Eigen::Vector3d;

// ---------------------------------------------------------------- tag layouts

TagLayout parse_tag_layout(const std::string& text, const std::string& source) {
  const YAML::Node root = load(text, source);
  const Location top{source, ""};
  TagLayout layout;
  if (const YAML::Node family = root["family"]) {
    if (!family.IsScalar()) {
      throw HandEyeError(ErrorCode::MalformedFile, "`family` must be a name", (top / "family").str(),
                         "write e.g. `family: tag36h11`");
    }
    layout.family = family.Scalar();
  }
  const YAML::Node tags = require_list(root, "tags", top);
  const std::string hint = "a tag is {id: 0, size: 0.06, x: 0, y: 0, z: 0, qw: 1, qx: 0, qy: 0, qz: 0}";
  for (std::size_t i = 0; i < tags.size(); ++i) {
    const Location at = (top / "tags")[i];
    const YAML::Node entry = tags[i];
    TagPlacement tag;
    tag.id = as_integer(require(entry, "id", at, hint), at / "id", 0, 1e6, "the tag id");
    tag.size = as_double(require(entry, "size", at, hint), at / "size");
    const auto optional_number = [&](const char* key, double fallback) {
      const YAML::Node node = entry[key];
      return node ? as_double(node, at / key) : fallback;
    };
    const Vector3d t(optional_number("x", 0.0), optional_number("y", 0.0), optional_number("z", 0.0));
    const Eigen::Quaterniond q(optional_number("qw", 1.0), optional_number("qx", 0.0), optional_number("qy", 0.0),
                               optional_number("qz", 0.0));
    tag.T_pattern_tag = se3::make_pose(checked_unit_quaternion(q, at.str()).toRotationMatrix(), t);
    layout.tags.push_back(tag);
  }
  check_layout(layout, source);
  return layout;
}

TagLayout read_tag_layout(const std::string& path) { return parse_tag_layout(read_file(path), path); }

// ---------------------------------------------------------------- targets

namespace {

/// A target file's keys through the shared readers (yaml_primitives.h), every
/// refusal with the kind's example as its fix.
class YamlFields : public TargetFields {
 public:
  YamlFields(const YAML::Node& root, const Location& top, std::string hint)
      : root_(root), top_(top), hint_(std::move(hint)) {}

  bool has(const std::string& key) const override { return static_cast<bool>(root_[key]); }
  std::string text(const std::string& key) const override { return as_text(node(key), top_ / key); }
  double number(const std::string& key) const override { return as_double(node(key), top_ / key); }
  double length(const std::string& key) const override {
    const double v = number(key);
    if (!(v > 0.0 && v < 10.0)) refuse(key, "`" + key + "` must be a length in m, above 0 and below 10");
    return v;
  }
  int integer(const std::string& key, double lowest, double highest, const std::string& what) const override {
    return as_integer(node(key), top_ / key, lowest, highest, what);
  }
  std::array<int, 2> pair(const std::string& key, const std::string& what) const override {
    const YAML::Node n = node(key);
    if (!n.IsSequence() || n.size() != 2) {
      throw HandEyeError(ErrorCode::WrongLength, "`" + key + "` must be [columns, rows] (" + what + ")",
                         (top_ / key).str(), hint_);
    }
    return std::array<int, 2>{as_integer(n[0], (top_ / key)[0], 1, 1000, what),
                              as_integer(n[1], (top_ / key)[1], 1, 1000, what)};
  }
  [[noreturn]] void refuse(const std::string& key, const std::string& message) const override {
    throw HandEyeError(ErrorCode::InvalidLayout, message, (top_ / key).str(), hint_);
  }

 private:
  YAML::Node node(const std::string& key) const { return require(root_, key, top_, hint_); }

  YAML::Node root_;
  Location top_;
  std::string hint_;
};

}  // namespace

Target parse_target(const std::string& text, const std::string& source) {
  const YAML::Node root = load(text, source);
  const Location top{source, ""};
  if (root.IsMap() && root["tags"] && !root["type"]) return make_target(parse_tag_layout(text, source));
  const std::string type = as_text(require(root, "type", top, "write `type: " + target_file_types() + "` (docs/targets.md)"),
                                   top / "type");
  const TargetKind* kind = find_target_kind_of_type(type);
  if (!kind) {
    throw HandEyeError(ErrorCode::InvalidLayout, "unknown target type `" + type + "`", (top / "type").str(),
                       "use " + target_file_types());
  }
  return kind->parse(type, YamlFields(root, top, kind->example(type)));
}

Target read_target(const std::string& path) { return parse_target(read_file(path), path); }

// ---------------------------------------------------------------- camera_info

namespace {
Eigen::Vector4d intrinsics_sigma(const YAML::Node& node, const Location& at) {
  const auto values = as_numbers<4>(node, at, "the 1 sigma of fx, fy, cx, cy in px");
  const Eigen::Vector4d sigma(values[0], values[1], values[2], values[3]);
  if (!(sigma.array() >= 0.0).all()) {
    throw HandEyeError(ErrorCode::MalformedFile, "intrinsics_sigma holds a negative sigma", at.str(),
                       "give the 1 sigma of fx, fy, cx, cy in px, each >= 0 (e.g. from handeye images --refine-intrinsics)");
  }
  return sigma;
}
}  // namespace

CameraModel parse_camera_info(const std::string& text, const std::string& source) {
  const std::string hint = "a ROS camera_info YAML (camera_calibration writes one): image_width, image_height, "
                           "camera_matrix: {data: [9 numbers]}, distortion_coefficients: {data: [...]}";
  const YAML::Node root = load(text, source);
  const Location top{source, ""};
  if (!root.IsMap()) throw HandEyeError(ErrorCode::MalformedFile, "not a camera_info YAML", top.str(), hint);
  const auto numbers = [&](const char* key) {
    const Location at = top / key / "data";
    const YAML::Node data = require(require(root, key, top, hint), "data", top / key, hint);
    if (!data.IsSequence()) throw HandEyeError(ErrorCode::MalformedFile, "expected a list of numbers", at.str(), hint);
    std::vector<double> values;
    for (std::size_t i = 0; i < data.size(); ++i) {
      values.push_back(as_finite(data[i], at[i], "NaN or Inf", hint));
    }
    return values;
  };
  CameraModel camera;
  const std::vector<double> K = numbers("camera_matrix");
  if (K.size() != 9) {
    throw HandEyeError(ErrorCode::WrongLength, "camera_matrix needs 9 numbers, got " + std::to_string(K.size()),
                       (top / "camera_matrix" / "data").str(), hint);
  }
  for (int i = 0; i < 9; ++i) camera.K(i / 3, i % 3) = K[static_cast<std::size_t>(i)];
  if (root["distortion_coefficients"]) camera.distortion = numbers("distortion_coefficients");
  for (const auto& [key, member] : {std::pair<const char*, int*>{"image_width", &camera.width}, {"image_height", &camera.height}}) {
    if (root[key]) *member = as_integer(root[key], top / key, 0, 100000, std::string(key) + " (pixels)");
  }
  if (const YAML::Node sigma = root["intrinsics_sigma"]) camera.intrinsics_sigma = intrinsics_sigma(sigma, top / "intrinsics_sigma");
  return camera;
}

}  // namespace io
}  // namespace handeye
