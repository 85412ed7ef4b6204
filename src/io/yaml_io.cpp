#include "handeye_covariance/io/yaml_io.h"

#include <yaml-cpp/yaml.h>

#include <Eigen/SVD>

#include <atomic>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <set>
#include <type_traits>
#include <fstream>
#include <sstream>
#include <fcntl.h>
#include <unistd.h>

#include "handeye_covariance/core/validation.h"

namespace handeye {
namespace io {

namespace {

using Eigen::Isometry3d;
using Eigen::Matrix3d;
using Eigen::Vector3d;

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

/// A sample's corners (TargetCorners): the camera, the target points (m, pattern
/// frame) and their pixels (raw), flat; the corner-noise model's diagonal blocks
/// (`block` x `block`, row-major, per unit sigma^2; absent: independent corners).
void emit_corners(YAML::Emitter& out, const TargetCorners& c) {
  const PointCorrespondences& p = c.points;
  out << YAML::BeginMap;
  if (!c.source.empty()) out << YAML::Key << "source" << YAML::Value << c.source;
  out << YAML::Key << "camera" << YAML::Value << YAML::BeginMap;
  const auto K = to_row_major_3x3(c.camera.K);
  out << YAML::Key << "K" << YAML::Value;
  emit_numbers(out, K.data(), K.size());
  out << YAML::Key << "distortion" << YAML::Value;
  emit_numbers(out, c.camera.distortion.data(), c.camera.distortion.size());
  out << YAML::Key << "width" << YAML::Value << c.camera.width << YAML::Key << "height" << YAML::Value << c.camera.height;
  out << YAML::EndMap;
  std::vector<double> object, image;
  for (const Vector3d& o : p.object) object.insert(object.end(), {o.x(), o.y(), o.z()});
  for (const Eigen::Vector2d& u : p.image) image.insert(image.end(), {u.x(), u.y()});
  const std::vector<double> covariance = covariance_blocks(p);
  out << YAML::Key << "object" << YAML::Value;
  emit_numbers(out, object.data(), object.size());
  out << YAML::Key << "image" << YAML::Value;
  emit_numbers(out, image.data(), image.size());
  if (!p.ids.empty()) out << YAML::Key << "ids" << YAML::Value << YAML::Flow << p.ids;
  out << YAML::Key << "block" << YAML::Value << p.blocks;
  if (!covariance.empty()) {
    out << YAML::Key << "covariance" << YAML::Value;
    emit_numbers(out, covariance.data(), covariance.size());
  }
  out << YAML::EndMap;
}

TargetCorners read_corners(const YAML::Node& node, const Location& at) {
  const std::string hint = "corners are {camera: {K: [9], distortion: [...], width, height}, object: [x, y, z, ...], "
                           "image: [u, v, ...], block: 2, covariance?: [the diagonal blocks, row-major]}";
  if (!node.IsMap()) throw HandEyeError(ErrorCode::MalformedFile, "expected a map", at.str(), hint);
  TargetCorners c;
  if (node["source"]) c.source = as_text(node["source"], at / "source");
  const YAML::Node camera = require(node, "camera", at, hint);
  const auto K = as_numbers<9>(require(camera, "K", at / "camera", hint), at / "camera" / "K", "row-major 3x3");
  for (int i = 0; i < 9; ++i) c.camera.K(i / 3, i % 3) = K[static_cast<std::size_t>(i)];
  if (camera["distortion"]) {
    c.camera.distortion = as_number_list(camera["distortion"], at / "camera" / "distortion", "distortion");
  }
  for (const auto& [key, member] : {std::pair<const char*, int*>{"width", &c.camera.width}, {"height", &c.camera.height}}) {
    if (camera[key]) *member = as_integer(camera[key], at / "camera" / key, 0, 100000, std::string(key) + " (pixels)");
  }
  const std::vector<double> object = as_number_list(require(node, "object", at, hint), at / "object", "x, y, z per point");
  const std::vector<double> image = as_number_list(require(node, "image", at, hint), at / "image", "u, v per point");
  const std::size_t n = image.size() / 2;
  if (n > kMaxTargetPoints) {  // before its 2n x 2n covariance is allocated
    throw HandEyeError(ErrorCode::WrongLength, std::to_string(n) + " points", (at / "image").str(),
                       "a target has at most " + std::to_string(kMaxTargetPoints) + " points");
  }
  if (object.size() % 3 != 0 || image.size() % 2 != 0 || object.size() / 3 != n) {
    throw HandEyeError(ErrorCode::WrongLength,
                       std::to_string(object.size()) + " object numbers for " + std::to_string(image.size()) +
                           " image numbers",
                       at.str(), "give 3 numbers per point in object and 2 in image, the same points in the same order");
  }
  for (std::size_t i = 0; i < n; ++i) {
    c.points.object.emplace_back(object[3 * i], object[3 * i + 1], object[3 * i + 2]);
    c.points.image.emplace_back(image[2 * i], image[2 * i + 1]);
  }
  if (node["ids"]) {
    for (double id : as_number_list(node["ids"], at / "ids", "the tags, markers or corners used")) {
      c.points.ids.push_back(static_cast<int>(std::clamp(id, -1e9, 1e9)));
    }
  }
  if (node["block"]) {
    c.points.blocks = as_integer(node["block"], at / "block", 2, kMaxCornerBlock, "block (coordinates per block)");
  }
  const int b = c.points.blocks;
  if (b % 2 != 0 || (2 * n) % static_cast<std::size_t>(b) != 0) {
    throw HandEyeError(ErrorCode::WrongLength, "block " + std::to_string(b) + " does not divide the " + std::to_string(2 * n) +
                                                   " coordinates into whole points",
                       (at / "block").str(), "2 for independent corners, 8 for an AprilTag's four");
  }
  if (node["covariance"]) {
    const std::vector<double> blocks = as_number_list(node["covariance"], at / "covariance", "the diagonal blocks");
    const std::size_t m = 2 * n;
    if (blocks.size() != m * static_cast<std::size_t>(b)) {
      throw HandEyeError(ErrorCode::WrongLength,
                         "expected " + std::to_string(m * static_cast<std::size_t>(b)) + " numbers (" +
                             std::to_string(m / static_cast<std::size_t>(b)) + " blocks of " + std::to_string(b) + " x " +
                             std::to_string(b) + "), got " + std::to_string(blocks.size()),
                         (at / "covariance").str(), "give each block's numbers row-major, the blocks in order");
    }
    c.points.corner_covariance = from_covariance_blocks(blocks, b);
  }
  check_camera_model(c.camera, (at / "camera").str());
  check_corners(c.points, at.str());
  return c;
}

}  // namespace

// ---------------------------------------------------------------- samples

SampleSet parse_samples(const std::string& text, const std::string& source) {
  const YAML::Node root = load(text, source);
  const Location top{source, ""};
  SampleSet set;
  set.rig.setup = read_setup(require(root, "setup", top, "add `setup: eye_in_hand` or `setup: eye_to_hand`"),
                             top / "setup");
  if (const YAML::Node frames = root["frames"]; frames && frames.IsMap()) {
    auto name = [&](const char* key) { return frames[key] ? as_text(frames[key], top / "frames" / key) : std::string(); };
    set.rig.frames = {name("base"), name("effector"), name("camera"), name("pattern")};
  }
  if (root["pattern_face"]) set.rig.T_pattern_face = read_pose(root["pattern_face"], top / "pattern_face");
  if (const YAML::Node symmetric = root["pattern_symmetric"]) {
    set.rig.symmetric_face = as_bool(symmetric, top / "pattern_symmetric");
  }
  if (const YAML::Node size = root["pattern_face_size"]) {
    const auto wh = as_numbers<2>(size, top / "pattern_face_size", "the target's width and height, m");
    set.rig.face_size = Eigen::Vector2d(wh[0], wh[1]);
    if (!(set.rig.face_size.array() >= 0.0).all()) {
      throw HandEyeError(ErrorCode::MalformedFile, "the target's width and height must be lengths >= 0 (m)",
                         (top / "pattern_face_size").str(), "give [width, height] in m, e.g. [0.189, 0.118]");
    }
  }
  set.noise = optional_noise(root, top, "effector", "pattern");
  const YAML::Node list = require_list(root, "samples", top);
  for (std::size_t i = 0; i < list.size(); ++i) {
    const Location at = (top / "samples")[i];
    const YAML::Node node = list[i];
    const std::string hint = "a sample is {effector: pose, pattern: pose, stamp?, noise?, corners?}";
    PoseSample sample;
    sample.T_base_effector = read_pose(require(node, "effector", at, hint), at / "effector");
    sample.T_camera_pattern = read_pose(require(node, "pattern", at, hint), at / "pattern");
    if (node["stamp"]) sample.stamp = as_double(node["stamp"], at / "stamp");
    sample.noise = optional_noise(node, at, "effector", "pattern");
    if (node["corners"]) sample.corners = std::make_shared<const TargetCorners>(read_corners(node["corners"], at / "corners"));
    set.samples.push_back(sample);
  }
  return set;
}

SampleSet read_samples(const std::string& path) { return parse_samples(read_file(path), path); }

MeasurementNoise read_noise_file(const std::string& path) {
  const YAML::Node root = load(read_file(path), path);
  const Location top{path, ""};
  return read_noise(require(root, "noise", top, "the file needs a `noise: {effector: {rotation, translation}, "
                                                 "pattern: {rotation, translation}}` block"),
                    top / "noise", "effector", "pattern");
}

std::string format_samples(const SampleSet& set) {
  YAML::Emitter out;
  new_emitter(out) << YAML::BeginMap;
  out << YAML::Key << "setup" << YAML::Value << to_string(set.rig.setup);
  const FrameNames& f = set.rig.frames;
  if (!(f.base.empty() && f.effector.empty() && f.camera.empty() && f.pattern.empty())) {
    out << YAML::Key << "frames" << YAML::Value << YAML::Flow << YAML::BeginMap;
    out << YAML::Key << "base" << YAML::Value << f.base << YAML::Key << "effector" << YAML::Value
        << f.effector << YAML::Key << "camera" << YAML::Value << f.camera << YAML::Key << "pattern"
        << YAML::Value << f.pattern << YAML::EndMap;
  }
  if (set.rig.T_pattern_face.matrix() != Eigen::Matrix4d::Identity()) {
    emit_keyed_pose(out, "pattern_face", set.rig.T_pattern_face);  // where new views look (Rig)
  }
  if (set.rig.symmetric_face) {  // each view's pose is one of two candidates (Rig)
    out << YAML::Key << "pattern_symmetric" << YAML::Value << true;
  }
  if (!set.rig.face_size.isZero(0.0)) {  // the target's size: the view-following noise's shape (Rig)
    out << YAML::Key << "pattern_face_size" << YAML::Value << YAML::Flow << YAML::BeginSeq << set.rig.face_size.x()
        << set.rig.face_size.y() << YAML::EndSeq;
  }
  if (set.noise) {
    out << YAML::Key << "noise" << YAML::Value;
    emit_noise(out, *set.noise, "effector", "pattern");
  }
  out << YAML::Key << "samples" << YAML::Value << YAML::BeginSeq;
  for (const PoseSample& s : set.samples) {
    out << YAML::BeginMap;
    emit_keyed_pose(out, "effector", s.T_base_effector);
    emit_keyed_pose(out, "pattern", s.T_camera_pattern);
    if (s.stamp) out << YAML::Key << "stamp" << YAML::Value << *s.stamp;
    if (s.noise) {
      out << YAML::Key << "noise" << YAML::Value;
      emit_noise(out, *s.noise, "effector", "pattern");
    }
    if (s.corners) {
      out << YAML::Key << "corners" << YAML::Value;
      emit_corners(out, *s.corners);
    }
    out << YAML::EndMap;
  }
  out << YAML::EndSeq << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

// ---------------------------------------------------------------- motions

std::vector<Isometry3d> parse_candidate_poses(const std::string& text, const std::string& source) {
  const YAML::Node root = load(text, source);
  const Location top{source, ""};
  const YAML::Node list = require_list(root, "candidates", top);
  std::vector<Isometry3d> poses;
  for (std::size_t i = 0; i < list.size(); ++i) poses.push_back(read_pose(list[i], (top / "candidates")[i]));
  return poses;
}

std::vector<Isometry3d> read_candidate_poses(const std::string& path) {
  return parse_candidate_poses(read_file(path), path);
}

std::string format_suggestions(const Suggestion& suggestion, int count, const Plan& plan, double target_object_sigma,
                               const SuggestOptions& options) {
  YAML::Emitter out;
  new_emitter(out) << YAML::BeginMap;
  out << YAML::Key << "criterion" << YAML::Value << to_string(options.criterion);
  out << YAML::Key << "working_distance" << YAML::Value << options.working_distance;
  out << YAML::Key << "current_object_sigma_mm" << YAML::Value << suggestion.current_object_sigma * 1e3;
  const auto emit_scored = [&](const ScoredPose& p) {
    out << YAML::BeginMap;
    emit_pose(out, p.T_base_effector);
    out << YAML::Key << "object_sigma_mm" << YAML::Value << p.object_sigma * 1e3;
    out << YAML::Key << "score" << YAML::Value << p.score;
    out << YAML::EndMap;
  };
  out << YAML::Key << "suggestions" << YAML::Value << YAML::BeginSeq;  // T_base_effector, best first
  for (int i = 0; i < count && i < static_cast<int>(suggestion.ranked.size()); ++i) emit_scored(suggestion.ranked[i]);
  out << YAML::EndSeq;
  out << YAML::Key << "plan" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "target_object_sigma_mm" << YAML::Value << target_object_sigma * 1e3;
  out << YAML::Key << "reached" << YAML::Value << plan.reached;
  out << YAML::Key << "poses" << YAML::Value << YAML::BeginSeq;
  for (const ScoredPose& p : plan.poses) emit_scored(p);
  out << YAML::EndSeq << YAML::EndMap << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

std::string format_noise_estimate(const NoiseEstimate& estimate) {
  YAML::Emitter out;
  new_emitter(out) << YAML::BeginMap;
  out << YAML::Key << "noise" << YAML::Value;
  emit_noise(out, estimate.noise, "effector", "pattern");
  out << YAML::Key << "estimate" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "source" << YAML::Value << to_string(estimate.source);
  out << YAML::Key << "samples_used" << YAML::Value << estimate.samples_used;
  if (estimate.source == NoiseSource::RepeatedObservations) out << YAML::Key << "groups" << YAML::Value << estimate.groups;
  out << YAML::Key << "dof" << YAML::Value << estimate.dof;
  out << YAML::Key << "relative_variance_sigma" << YAML::Value << std::sqrt(2.0 / estimate.dof);
  out << YAML::Key << "robot_identified" << YAML::Value << estimate.robot_identified;
  const auto sigmas = [&](const char* key, const Matrix3d& covariance, double unit) {
    const Vector3d sigma = covariance.diagonal().cwiseMax(0.0).cwiseSqrt() * unit;
    out << YAML::Key << key << YAML::Value;
    emit_numbers(out, sigma.data(), 3);
  };
  sigmas("pattern_sigma_mm", estimate.noise.camera.translation, 1e3);
  sigmas("pattern_sigma_deg", estimate.noise.camera.rotation, 180.0 / M_PI);
  sigmas("effector_sigma_mm", estimate.noise.robot.translation, 1e3);
  sigmas("effector_sigma_deg", estimate.noise.robot.rotation, 180.0 / M_PI);
  out << YAML::Key << "notes" << YAML::Value << estimate.notes;
  out << YAML::EndMap << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

MotionSet parse_motions(const std::string& text, const std::string& source) {
  const YAML::Node root = load(text, source);
  const Location top{source, ""};
  MotionSet set;
  set.noise = optional_noise(root, top, "A", "B");
  const YAML::Node list = require_list(root, "motions", top);
  for (std::size_t i = 0; i < list.size(); ++i) {
    const Location at = (top / "motions")[i];
    const std::string hint = "a motion is {A: pose, B: pose, noise?}";
    MotionPair pair;
    pair.A = read_pose(require(list[i], "A", at, hint), at / "A");
    pair.B = read_pose(require(list[i], "B", at, hint), at / "B");
    pair.noise = optional_noise(list[i], at, "A", "B");
    set.motions.push_back(pair);
  }
  return set;
}

MotionSet read_motions(const std::string& path) { return parse_motions(read_file(path), path); }

std::string format_motions(const MotionSet& set) {
  YAML::Emitter out;
  new_emitter(out) << YAML::BeginMap;
  if (set.noise) {
    out << YAML::Key << "noise" << YAML::Value;
    emit_noise(out, *set.noise, "A", "B");
  }
  out << YAML::Key << "motions" << YAML::Value << YAML::BeginSeq;
  for (const MotionPair& m : set.motions) {
    out << YAML::BeginMap;
    emit_keyed_pose(out, "A", m.A);
    emit_keyed_pose(out, "B", m.B);
    if (m.noise) {
      out << YAML::Key << "noise" << YAML::Value;
      emit_noise(out, *m.noise, "A", "B");
    }
    out << YAML::EndMap;
  }
  out << YAML::EndSeq << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

Input read_input(const std::string& path) {
  const std::string text = read_file(path);
  const YAML::Node root = load(text, path);
  if (root["samples"]) return parse_samples(text, path);
  if (root["motions"]) return parse_motions(text, path);
  throw HandEyeError(ErrorCode::MissingKey, "the file has neither a `samples` nor a `motions` list", path,
                     "give a samples file (robot and pattern poses) or a motions file (A, B pairs); "
                     "see docs/file_formats.md");
}

// ---------------------------------------------------------------- results

ResultContext context_of(const SampleSet& samples) {
  ResultContext c;
  c.setup = samples.rig.setup;
  c.parent = samples.rig.camera_parent_frame();
  c.child = samples.rig.frames.camera;
  c.pattern_parent = samples.rig.pattern_parent_frame();
  c.pattern_child = samples.rig.frames.pattern;
  return c;
}

ResultContext context_of(const MotionSet&) { return {}; }

namespace {
/// The keys every result file has: frames, X, its covariance, the sample count
/// and easy_handeye's `transformation` block.
/// `covariance: {rotation, translation, pose}` of a pose.
void emit_pose_covariance(YAML::Emitter& out, const Matrix6d& covariance) {
  out << YAML::Key << "covariance" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "rotation" << YAML::Value;
  emit_covariance3(out, covariance.bottomRightCorner<3, 3>());
  out << YAML::Key << "translation" << YAML::Value;
  emit_covariance3(out, covariance.topLeftCorner<3, 3>());
  out << YAML::Key << "pose" << YAML::Value;
  const auto pose = to_row_major_6x6(covariance);
  emit_numbers(out, pose.data(), pose.size());
  out << YAML::EndMap;
}

void emit_result_head(YAML::Emitter& out, const PoseWithCovariance& X, int samples_used,
                      const ResultContext& context) {
  if (context.setup) out << YAML::Key << "setup" << YAML::Value << to_string(*context.setup);
  out << YAML::Key << "parent" << YAML::Value << context.parent;
  out << YAML::Key << "child" << YAML::Value << context.child;
  emit_pose(out, X.pose);
  emit_pose_covariance(out, X.covariance);
  out << YAML::Key << "samples_used" << YAML::Value << samples_used;

  Eigen::Quaterniond q(X.pose.linear());
  if (q.w() < 0) q.coeffs() *= -1.0;
  out << YAML::Key << "transformation" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "x" << YAML::Value << X.pose.translation().x();
  out << YAML::Key << "y" << YAML::Value << X.pose.translation().y();
  out << YAML::Key << "z" << YAML::Value << X.pose.translation().z();
  out << YAML::Key << "qx" << YAML::Value << q.x() << YAML::Key << "qy" << YAML::Value << q.y();
  out << YAML::Key << "qz" << YAML::Value << q.z() << YAML::Key << "qw" << YAML::Value << q.w();
  out << YAML::EndMap;
}
}  // namespace

std::string format_pose_file(const PoseWithCovariance& X, const ResultContext& context) {
  YAML::Emitter out;
  new_emitter(out) << YAML::BeginMap;
  emit_result_head(out, X, 0, context);
  out << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

std::string format_report(const CalibrationReport& report, const ResultContext& context, const std::string& source) {
  // Humans read this file: mm and degrees, in ROS order (x, y, z, rx, ry, rz).
  const auto human = [](const Vector6d& sigma) {
    std::vector<double> v(6);
    for (int k = 0; k < 6; ++k) v[static_cast<std::size_t>(k)] = sigma(k) * (k < 3 ? 1e3 : 180.0 / M_PI);
    return v;
  };
  const auto emit_list = [](YAML::Emitter& out, const std::vector<double>& v) { emit_numbers(out, v.data(), v.size()); };
  YAML::Emitter out;
  new_emitter(out) << YAML::BeginMap;
  out << YAML::Key << "source" << YAML::Value << source;
  if (context.setup) out << YAML::Key << "setup" << YAML::Value << to_string(*context.setup);
  out << YAML::Key << "frames" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key << "parent" << YAML::Value
      << context.parent << YAML::Key << "camera" << YAML::Value << context.child << YAML::EndMap;
  out << YAML::Key << "method" << YAML::Value << to_string(report.calibration.method);
  out << YAML::Key << "advice_sigma" << YAML::Value << report.advice_sigma;
  out << YAML::Key << "object" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key << "working_distance_m"
      << YAML::Value << report.working_distance << YAML::Key << "sigma_mm" << YAML::Value << report.object_sigma * 1e3
      << YAML::Key << "target_mm" << YAML::Value << report.target_object_sigma * 1e3 << YAML::EndMap;

  out << YAML::Key << "samples" << YAML::Value << YAML::BeginSeq;
  for (std::size_t i = 0; i < report.fits.size(); ++i) {
    const SampleFit& f = report.fits[i];
    const Calibration::Rejected* rejected = rejection_of(report.calibration, static_cast<int>(i));
    out << YAML::Flow << YAML::BeginMap << YAML::Key << "index" << YAML::Value << i << YAML::Key << "residual_mm"
        << YAML::Value << f.translation * 1e3 << YAML::Key << "residual_deg" << YAML::Value
        << f.rotation * 180.0 / M_PI << YAML::Key << "sigma" << YAML::Value << f.sigmas << YAML::Key << "rejected"
        << YAML::Value << (rejected != nullptr);
    if (rejected) out << YAML::Key << "reason" << YAML::Value << rejected->reason;
    out << YAML::EndMap;
  }
  out << YAML::EndSeq;

  out << YAML::Key << "checks" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "units" << YAML::Value << "mm, mm, mm, deg, deg, deg (x, y, z, rx, ry, rz)";
  out << YAML::Key << "predicted_sigma" << YAML::Value;
  emit_list(out, human(report.predicted_sigma));
  out << YAML::Key << "leave_one_out_sigma" << YAML::Value;
  emit_list(out, human(report.leave_one_out_sigma));
  out << YAML::Key << "leave_one_out_solved" << YAML::Value << report.leave_one_out_solved;
  out << YAML::Key << "leave_one_out_failed" << YAML::Value << report.leave_one_out_failed;
  out << YAML::Key << "split_half_sigma" << YAML::Value;
  emit_list(out, human(report.split_half_sigma));
  out << YAML::Key << "split_half_splits" << YAML::Value << report.honesty.observed.splits;
  out << YAML::Key << "split_half_size" << YAML::Value << report.honesty.observed.half_size;
  out << YAML::Key << "split_half_nees" << YAML::Value << report.honesty.observed.mean_nees;
  out << YAML::Key << "split_half_nees_translation" << YAML::Value << report.honesty.observed.mean_nees_translation;
  out << YAML::Key << "split_half_nees_rotation" << YAML::Value << report.honesty.observed.mean_nees_rotation;
  // The calibrated check: the middle 90% of the splits against an honest covariance on these poses.
  const HonestyCheck& h = report.honesty;
  out << YAML::Key << "split_half_nees_middle" << YAML::Value << h.observed.trimmed_mean_nees;
  out << YAML::Key << "honest_nees" << YAML::Value << h.reference.mean;
  out << YAML::Key << "honest_nees_band" << YAML::Value << YAML::Flow << YAML::BeginSeq << h.reference.low << h.reference.high
      << YAML::EndSeq;
  out << YAML::Key << "honest_sessions" << YAML::Value << h.reference.replicates;
  out << YAML::Key << "honesty_ratio" << YAML::Value << h.ratio;
  out << YAML::Key << "honesty" << YAML::Value << (h.ran() ? to_string(h.verdict) : "not run");
  out << YAML::Key << "honesty_text" << YAML::Value << (h.text.empty() ? std::string("not run") : h.text);
  if (!report.split_problem.empty()) out << YAML::Key << "split_half_problem" << YAML::Value << report.split_problem;
  out << YAML::EndMap;

  out << YAML::Key << "rotation_axes" << YAML::Value << YAML::BeginSeq;  // camera frame: x, y, z, angle (deg)
  for (const MotionAxis& m : report.rotation_axes) {
    emit_list(out, {m.axis.x(), m.axis.y(), m.axis.z(), m.angle * 180.0 / M_PI});
  }
  out << YAML::EndSeq;
  out << YAML::Key << "turning" << YAML::Value << YAML::BeginMap;  // eigen-decomposition of sum theta^2 a a^T, ascending
  out << YAML::Key << "eigenvalues_rad2" << YAML::Value;
  emit_list(out, {report.turning(0), report.turning(1), report.turning(2)});
  out << YAML::Key << "axes" << YAML::Value << YAML::BeginSeq;
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d a = report.turning_axes.col(k);
    emit_list(out, {a.x(), a.y(), a.z()});
  }
  out << YAML::EndSeq << YAML::EndMap;

  out << YAML::Key << "advice" << YAML::Value << YAML::BeginSeq;
  for (const std::string& a : report.advice) out << a;
  out << YAML::EndSeq << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

std::string format_result(const Calibration& calibration, const ResultContext& context) {
  YAML::Emitter out;
  new_emitter(out) << YAML::BeginMap;
  emit_result_head(out, {calibration.T_parent_camera, calibration.pose_covariance}, calibration.samples_used, context);
  out << YAML::Key << "motions_used" << YAML::Value << calibration.motions_used;
  out << YAML::Key << "method" << YAML::Value << to_string(calibration.method);
  if (calibration.pattern) {  // Y with the same keys as X, and Cov(X, Y)
    out << YAML::Key << "pattern" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "parent" << YAML::Value << context.pattern_parent;
    out << YAML::Key << "child" << YAML::Value << context.pattern_child;
    emit_pose(out, calibration.pattern->pose);
    emit_pose_covariance(out, calibration.pattern->covariance);
    out << YAML::EndMap;
    out << YAML::Key << "cross_covariance" << YAML::Value;  // 6x6, X's ROS order in rows, Y's in columns
    const auto cross = to_row_major_6x6(calibration.cross_covariance);
    emit_numbers(out, cross.data(), cross.size());
  }
  if (calibration.corner_fit) {  // method corners: the reprojection fit, per image
    const Calibration::CornerFit& fit = *calibration.corner_fit;
    out << YAML::Key << "corners" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "pixel_sigma" << YAML::Value << fit.pixel_sigma;
    out << YAML::Key << "pixel_sigma_estimated" << YAML::Value << fit.pixel_sigma_estimated;
    out << YAML::Key << "rms_px" << YAML::Value << fit.rms_px;
    out << YAML::Key << "corners" << YAML::Value << fit.corners;
    out << YAML::Key << "robot_poses" << YAML::Value << fit.robot;
    out << YAML::Key << "target_point_sigma" << YAML::Value << fit.target_point_sigma;  // m, per axis
    if (!fit.target_points.empty()) out << YAML::Key << "target_points" << YAML::Value << fit.target_points;
    if (!fit.pixel_noise.empty()) out << YAML::Key << "pixel_noise" << YAML::Value << fit.pixel_noise;
    out << YAML::Key << "per_image_sigma" << YAML::Value << fit.per_image_sigma;
    if (!fit.intrinsics.empty()) {  // refined: fx, fy, cx, cy (px), k1, k2, each with its 1 sigma
      const char* names[] = {"fx", "fy", "cx", "cy", "k1", "k2"};
      out << YAML::Key << "intrinsics" << YAML::Value << YAML::BeginMap;
      for (std::size_t k = 0; k < fit.intrinsics.size(); ++k) {
        out << YAML::Key << names[k] << YAML::Value << YAML::Flow << YAML::BeginSeq << fit.intrinsics[k]
            << fit.intrinsics_sigma[k] << YAML::EndSeq;
      }
      out << YAML::EndMap;
    }
    out << YAML::Key << "images" << YAML::Value << YAML::BeginSeq;
    for (const Calibration::CornerFit::Image& image : fit.images) {
      out << YAML::Flow << YAML::BeginMap << YAML::Key << "image" << YAML::Value << image.name << YAML::Key << "corners"
          << YAML::Value << image.corners << YAML::Key << "rms_px" << YAML::Value << image.rms_px << YAML::Key
          << "sigma_px" << YAML::Value << image.sigma_px << YAML::EndMap;
    }
    out << YAML::EndSeq << YAML::EndMap;
  }

  const bool samples = context.setup.has_value();
  out << YAML::Key << "noise" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "origin" << YAML::Value
      << (calibration.noise_origin == NoiseOrigin::Given ? "given" : "estimated_from_residuals");
  out << YAML::Key << "model" << YAML::Value;
  emit_noise(out, calibration.noise, samples ? "effector" : "A", samples ? "pattern" : "B");
  if (!calibration.noise_model.empty()) out << YAML::Key << "how" << YAML::Value << calibration.noise_model;
  if (!calibration.noise_components.empty()) {  // joint: each number the residuals estimated, with its 1 sigma
    out << YAML::Key << "estimated" << YAML::Value << YAML::BeginSeq;
    for (const Calibration::NoiseComponent& c : calibration.noise_components) {
      out << YAML::Flow << YAML::BeginMap << YAML::Key << "name" << YAML::Value << c.name << YAML::Key << "value"
          << YAML::Value << c.value << YAML::Key << "sigma" << YAML::Value << c.sigma << YAML::Key << "unit" << YAML::Value
          << c.unit << YAML::Key << "supported" << YAML::Value << !c.at_bound << YAML::EndMap;
    }
    out << YAML::EndSeq;
  }
  if (!calibration.noise_candidates.empty()) {  // joint: the noise models compared by BIC
    out << YAML::Key << "candidates" << YAML::Value << YAML::BeginSeq;
    for (const Calibration::NoiseCandidate& c : calibration.noise_candidates) {
      out << YAML::Flow << YAML::BeginMap << YAML::Key << "name" << YAML::Value << c.name << YAML::Key << "numbers"
          << YAML::Value << c.numbers << YAML::Key << "score" << YAML::Value << c.score << YAML::Key << "fitted" << YAML::Value
          << c.fitted << YAML::Key << "chosen" << YAML::Value << c.chosen;
      if (c.fitted) {
        out << YAML::Key << "log_likelihood" << YAML::Value << c.log_likelihood << YAML::Key << "bic" << YAML::Value << c.bic;
      }
      out << YAML::EndMap;
    }
    out << YAML::EndSeq;
  }
  if (const auto& m = calibration.residual_noise) {
    // The residual covariance of any view (joint_estimator.h residual_covariances):
    // S = camera_scale Sigma_P + camera + view_scale G(P) + D (Sigma_E + robot) D^T.
    out << YAML::Key << "residual_model" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "camera_scale" << YAML::Value << m->camera_scale;
    const auto camera = to_row_major_6x6(m->camera), robot = to_row_major_6x6(m->robot);
    out << YAML::Key << "camera" << YAML::Value;
    emit_numbers(out, camera.data(), camera.size());
    out << YAML::Key << "robot" << YAML::Value;
    emit_numbers(out, robot.data(), robot.size());
    out << YAML::Key << "view_scale" << YAML::Value << m->view_scale;
    if (!m->view_points.empty()) {
      std::vector<double> points;
      for (const Eigen::Vector3d& p : m->view_points) points.insert(points.end(), {p.x(), p.y(), p.z()});
      out << YAML::Key << "view_points" << YAML::Value;
      emit_numbers(out, points.data(), points.size());
    }
    out << YAML::EndMap;
  }
  out << YAML::EndMap;
  if (!calibration.turned.empty()) {  // a symmetric target: the views turned to agree with the motion
    out << YAML::Key << "turned_samples" << YAML::Value << YAML::Flow << calibration.turned;
  }
  if (const auto& h = calibration.honesty) {  // the calibrated split-half check (split_check.h)
    out << YAML::Key << "honesty" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "verdict" << YAML::Value << h->verdict;
    out << YAML::Key << "text" << YAML::Value << h->text;
    if (h->verdict != "not run") {
      out << YAML::Key << "splits" << YAML::Value << h->splits << YAML::Key << "half_size" << YAML::Value << h->half_size;
      out << YAML::Key << "split_half_nees" << YAML::Value << h->split_half_nees;
      out << YAML::Key << "reference" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key << "sessions"
          << YAML::Value << h->replicates << YAML::Key << "mean" << YAML::Value << h->reference_mean << YAML::Key << "low"
          << YAML::Value << h->reference_low << YAML::Key << "high" << YAML::Value << h->reference_high << YAML::EndMap;
      out << YAML::Key << "ratio" << YAML::Value << h->ratio;
      out << YAML::Key << "inflation" << YAML::Value << h->inflation;
      if (h->inflation > 1.0) {  // X's covariance as the noise model gave it; the one above is inflated
        const auto model = to_row_major_6x6(h->model_pose_covariance);
        out << YAML::Key << "model_covariance" << YAML::Value;
        emit_numbers(out, model.data(), model.size());
      }
    }
    out << YAML::EndMap;
  }
  if (const auto& p = calibration.prediction) {  // leave-one-out: how well it predicts a view it has not seen
    out << YAML::Key << "prediction" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key << "scale" << YAML::Value
        << p->scale << YAML::Key << "dof" << YAML::Value << p->dof << YAML::Key << "views" << YAML::Value << p->views
        << YAML::EndMap;
  }
  if (calibration.method == Method::Joint) {  // which tests ran on the residuals, and what they chose
    out << YAML::Key << "residual_checks" << YAML::Value << YAML::BeginSeq;
    for (const Calibration::ResidualCheck& c : calibration.residual_checks) {
      out << YAML::Flow << YAML::BeginMap << YAML::Key << "test" << YAML::Value << c.test << YAML::Key << "statistic"
          << YAML::Value << c.statistic << YAML::Key << "bound" << YAML::Value << c.bound << YAML::Key << "passed"
          << YAML::Value << c.passed << YAML::EndMap;
    }
    out << YAML::EndSeq;
    out << YAML::Key << "robust" << YAML::Value << YAML::Flow << YAML::BeginMap;
    out << YAML::Key << "loss" << YAML::Value << calibration.loss;
    out << YAML::Key << "covariance" << YAML::Value << calibration.covariance_kind;
    out << YAML::Key << "downweighted" << YAML::Value << calibration.downweighted;
    out << YAML::Key << "covariance_inflation" << YAML::Value << calibration.covariance_inflation;
    out << YAML::Key << "pattern_covariance_inflation" << YAML::Value << calibration.pattern_covariance_inflation;
    out << YAML::EndMap;
  }

  out << YAML::Key << "solver" << YAML::Value << YAML::BeginMap;
  for (const auto& [name, stage] : {std::pair<const char*, const StageDiagnostics*>{"rotation", &calibration.rotation_stage},
                                    {"translation", &calibration.translation_stage}}) {
    out << YAML::Key << name << YAML::Value << YAML::Flow << YAML::BeginMap;
    out << YAML::Key << "iterations" << YAML::Value << stage->iterations;
    out << YAML::Key << "stop_reason" << YAML::Value << to_string(stage->stop_reason);
    out << YAML::Key << "chi2" << YAML::Value << stage->chi2;
    out << YAML::Key << "dof" << YAML::Value << stage->dof;
    out << YAML::EndMap;
  }
  out << YAML::EndMap;
  out << YAML::Key << "warnings" << YAML::Value << YAML::Flow << calibration.warnings;
  out << YAML::Key << "rejected" << YAML::Value << YAML::BeginSeq;  // outliers left out, indices into the input
  for (const auto& r : calibration.rejected) {
    out << YAML::Flow << YAML::BeginMap << YAML::Key << "index" << YAML::Value << r.index << YAML::Key << "reason"
        << YAML::Value << r.reason << YAML::EndMap;
  }
  out << YAML::EndSeq;
  out << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

std::string format_check(const CalibrationCheck& check, const std::string& calibration_path) {
  YAML::Emitter out;
  new_emitter(out) << YAML::BeginMap;
  const auto emit_6 = [&](const char* key, const Vector6d& v) {
    out << YAML::Key << key << YAML::Value;
    emit_numbers(out, v.data(), 6);
  };
  const auto emit_6x6 = [&](const char* key, const Matrix6d& m) {
    const auto rows = to_row_major_6x6(m);
    out << YAML::Key << key << YAML::Value;
    emit_numbers(out, rows.data(), rows.size());
  };
  out << YAML::Key << "calibration" << YAML::Value << calibration_path;
  out << YAML::Key << "verdict" << YAML::Value << (check.changed ? "changed" : "consistent");
  out << YAML::Key << "p_value" << YAML::Value << check.p_value;
  out << YAML::Key << "alpha" << YAML::Value << check.alpha;
  out << YAML::Key << "text" << YAML::Value << check.verdict;
  if (check.changed) {
    out << YAML::Key << "changed" << YAML::Value << check.change.what;
    const EstimatedChange::Delta& main = check.change.reported();
    emit_6("change", main.value);  // ROS order, m and rad: the new pose is exp(change) times the saved one
    emit_6x6("change_covariance", main.covariance);
    if (check.change.what == "both") {
      emit_6("pattern_change", check.change.Y_change->value);
      emit_6x6("pattern_change_covariance", check.change.Y_change->covariance);
    }
  }
  out << YAML::Key << "statistic" << YAML::Value << check.statistic;  // max(T_X, T_Y)
  out << YAML::Key << "chi2" << YAML::Value << check.chi2;
  out << YAML::Key << "dof" << YAML::Value << check.dof;
  out << YAML::Key << "chi2_p_value" << YAML::Value << check.chi2_p_value;
  out << YAML::Key << "hypotheses" << YAML::Value << YAML::BeginSeq;
  for (const EstimatedChange* h : {&check.X_alone, &check.Y_alone, &check.both}) {
    if (h->what.empty()) continue;  // both: not identified from one or two views
    out << YAML::Flow << YAML::BeginMap << YAML::Key << "changed" << YAML::Value << h->what << YAML::Key << "chi2_drop"
        << YAML::Value << h->chi2_drop << YAML::Key << "dof" << YAML::Value << h->dof << YAML::Key << "residual_chi2"
        << YAML::Value << h->residual_chi2 << YAML::Key << "residual_p_value" << YAML::Value << h->residual_p_value
        << YAML::EndMap;
  }
  out << YAML::EndSeq;
  out << YAML::Key << "views" << YAML::Value << YAML::BeginSeq;  // humans read these: mm and degrees
  for (std::size_t i = 0; i < check.views.size(); ++i) {
    const CheckedView& v = check.views[i];
    const bool left_out = std::find(check.left_out.begin(), check.left_out.end(), static_cast<int>(i)) != check.left_out.end();
    out << YAML::Flow << YAML::BeginMap << YAML::Key << "left_out" << YAML::Value << left_out << YAML::Key << "translation_mm" << YAML::Value << v.translation_error * 1e3
        << YAML::Key << "predicted_translation_mm" << YAML::Value << v.predicted_translation_sigma * 1e3 << YAML::Key
        << "rotation_deg" << YAML::Value << v.rotation_error * 180.0 / M_PI << YAML::Key << "predicted_rotation_deg"
        << YAML::Value << v.predicted_rotation_sigma * 180.0 / M_PI << YAML::Key << "sigma" << YAML::Value << v.mahalanobis
        << YAML::EndMap;
  }
  out << YAML::EndSeq;
  out << YAML::Key << "advice" << YAML::Value << YAML::BeginSeq;
  for (const std::string& a : check.advice) out << a;
  out << YAML::EndSeq << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

namespace {
/// `covariance: {pose: [36]}` (ROS order, wins when present) or
/// `{rotation: [9], translation: [9]}` (no cross block).
Matrix6d read_pose_covariance(const YAML::Node& covariance, const Location& at) {
  if (!covariance.IsMap()) {
    throw HandEyeError(ErrorCode::MalformedFile, "`covariance` must be a map", at.str(),
                       "write covariance: {pose: [36 numbers]} or {rotation: [9], translation: [9]}");
  }
  Matrix6d c;
  if (covariance["pose"]) {
    c = from_row_major_6x6(as_numbers<36>(covariance["pose"], at / "pose", "6x6 covariance, ROS order"));
  } else {
    c = read_covariance(covariance, at).as_pose_covariance();
  }
  check_covariance(c, at.str());
  return c;
}
}  // namespace

PoseFile parse_pose_file(const std::string& text, const std::string& source) {
  const YAML::Node root = load(text, source);
  const Location top{source, ""};
  PoseFile file;
  if (root["parent"] && root["parent"].IsScalar()) file.parent = root["parent"].Scalar();
  if (root["child"] && root["child"].IsScalar()) file.child = root["child"].Scalar();
  file.value.pose = read_pose(root, top);
  if (const YAML::Node covariance = root["covariance"]) {
    file.value.covariance = read_pose_covariance(covariance, top / "covariance");
    file.has_covariance = true;
  }
  return file;
}

PoseFile read_pose_file(const std::string& path) { return parse_pose_file(read_file(path), path); }

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

namespace {
CalibrationFile read_result_node(const YAML::Node& root, const Location& top) {
  CalibrationFile file;
  if (root["setup"]) file.context.setup = read_setup(root["setup"], top / "setup");
  if (root["parent"] && root["parent"].IsScalar()) file.context.parent = root["parent"].Scalar();
  if (root["child"] && root["child"].IsScalar()) file.context.child = root["child"].Scalar();
  file.T_parent_camera.pose = read_pose(root, top);
  const std::string hint = "the result file needs `covariance: {rotation, translation, pose}`";
  file.T_parent_camera.covariance = read_pose_covariance(require(root, "covariance", top, hint), top / "covariance");
  if (root["samples_used"]) file.samples_used = as_integer(root["samples_used"], top / "samples_used", 0, 1e9, "samples_used");
  // The noise model the calibration used (samples results only).
  if (const YAML::Node noise = root["noise"];
      noise && noise.IsMap() && noise["model"] && noise["model"].IsMap() && noise["model"]["effector"]) {
    file.noise = read_noise(noise["model"], top / "noise" / "model", "effector", "pattern");
    if (noise["origin"] && noise["origin"].IsScalar() && noise["origin"].Scalar() != "given") {
      file.noise_origin = NoiseOrigin::EstimatedFromResiduals;
    }
  }
  if (const YAML::Node pattern = root["pattern"]; pattern && pattern.IsMap()) {  // a joint result: Y and Cov(X, Y)
    const Location at = top / "pattern";
    PoseWithCovariance Y;
    Y.pose = read_pose(pattern, at);
    Y.covariance = read_pose_covariance(require(pattern, "covariance", at, hint), at / "covariance");
    file.pattern = Y;
    file.context.pattern_parent = pattern["parent"] && pattern["parent"].IsScalar() ? pattern["parent"].Scalar() : "";
    file.context.pattern_child = pattern["child"] && pattern["child"].IsScalar() ? pattern["child"].Scalar() : "";
    file.cross_covariance = from_row_major_6x6(as_numbers<36>(
        require(root, "cross_covariance", top, "a joint result with `pattern` has `cross_covariance` (36 numbers)"),
        top / "cross_covariance", "6x6 Cov(X, Y), X's ROS order in rows"));
  }
  if (const YAML::Node model = root["noise"] && root["noise"].IsMap() ? root["noise"]["residual_model"] : YAML::Node();
      model && model.IsMap()) {
    const Location at = top / "noise" / "residual_model";
    const std::string model_hint = "`residual_model` is {camera_scale, camera: [36], robot: [36], view_scale, view_points}";
    Calibration::ResidualNoise m;
    m.camera_scale = as_finite(require(model, "camera_scale", at, model_hint), at / "camera_scale", "NaN in camera_scale",
                               model_hint);
    m.camera = from_row_major_6x6(as_numbers<36>(require(model, "camera", at, model_hint), at / "camera", "6x6, ROS order"));
    m.robot = from_row_major_6x6(as_numbers<36>(require(model, "robot", at, model_hint), at / "robot", "6x6, ROS order"));
    check_covariance(m.camera, (at / "camera").str());
    check_covariance(m.robot, (at / "robot").str());
    if (model["view_scale"]) m.view_scale = as_finite(model["view_scale"], at / "view_scale", "NaN in view_scale", model_hint);
    if (model["view_points"]) {
      const std::vector<double> points = as_number_list(model["view_points"], at / "view_points", "x, y, z of each point");
      if (points.size() % 3 != 0) {
        throw HandEyeError(ErrorCode::WrongLength, "`view_points` needs 3 numbers per point", (at / "view_points").str(),
                           model_hint);
      }
      for (std::size_t i = 0; i + 2 < points.size(); i += 3) m.view_points.emplace_back(points[i], points[i + 1], points[i + 2]);
    }
    file.residual_noise = m;
  }
  if (const YAML::Node estimated = root["noise"] && root["noise"].IsMap() ? root["noise"]["estimated"] : YAML::Node();
      estimated && estimated.IsSequence()) {  // each estimated noise number with its 1 sigma: how well the noise is known
    const Location at = top / "noise" / "estimated";
    const std::string hint = "each entry is {name, value, sigma, unit, supported}";
    for (std::size_t i = 0; i < estimated.size(); ++i) {
      const YAML::Node e = estimated[i];
      Calibration::NoiseComponent c;
      c.name = as_text(require(e, "name", at[i], hint), at[i] / "name");
      c.value = as_finite(require(e, "value", at[i], hint), at[i] / "value", "NaN in a noise value", hint);
      c.sigma = as_finite(require(e, "sigma", at[i], hint), at[i] / "sigma", "NaN in a noise sigma", hint);
      if (e["unit"]) c.unit = e["unit"].IsNull() ? "" : as_text(e["unit"], at[i] / "unit");
      if (e["supported"]) c.at_bound = !as_bool(e["supported"], at[i] / "supported");
      file.noise_components.push_back(c);
    }
  }
  if (const YAML::Node prediction = root["prediction"]; prediction && prediction.IsMap()) {
    const Location at = top / "prediction";
    const std::string hint = "`prediction` is {scale, dof, views}: the leave-one-out of the calibration's views";
    Calibration::Prediction p;
    p.scale = as_finite(require(prediction, "scale", at, hint), at / "scale", "NaN in the prediction scale", hint);
    p.dof = as_finite(require(prediction, "dof", at, hint), at / "dof", "NaN in the prediction dof", hint);
    if (prediction["views"]) p.views = as_integer(prediction["views"], at / "views", 0, 1e9, "views");
    if (!(p.scale > 0.0) || !(p.dof > 0.0)) {
      throw HandEyeError(ErrorCode::MalformedFile, "the prediction scale and dof must be positive", at.str(), hint);
    }
    file.prediction = p;
  }
  if (const YAML::Node honesty = root["honesty"]; honesty && honesty.IsMap() && honesty["inflation"]) {
    file.inflation = as_finite(honesty["inflation"], top / "honesty" / "inflation", "NaN in the inflation",
                               "the honesty check's inflation is a number >= 1");
  }
  return file;
}
}  // namespace

CalibrationFile parse_result(const std::string& text, const std::string& source) {
  return read_result_node(load(text, source), Location{source, ""});
}

CalibrationFile read_result(const std::string& path) { return parse_result(read_file(path), path); }

Calibration calibration_of(const CalibrationFile& file) {
  Calibration c;
  c.method = Method::Joint;
  c.T_parent_camera = file.T_parent_camera.pose;
  c.pose_covariance = file.T_parent_camera.covariance;
  c.rotation_covariance = c.pose_covariance.bottomRightCorner<3, 3>();
  c.translation_covariance = c.pose_covariance.topLeftCorner<3, 3>();
  c.pattern = file.pattern;
  c.cross_covariance = file.cross_covariance;
  c.residual_noise = file.residual_noise;
  c.noise_components = file.noise_components;
  c.prediction = file.prediction;
  c.noise_origin = file.noise_origin;
  if (file.noise) c.noise = *file.noise;
  c.samples_used = file.samples_used;
  if (file.inflation > 1.0) {
    Calibration::Honesty h;
    h.inflation = file.inflation;
    h.verdict = "overconfident";
    c.honesty = h;
  }
  return c;
}

StoredCalibration parse_stored_calibration(const std::string& text, const std::string& source) {
  const YAML::Node root = load(text, source);
  const Location top{source, ""};
  StoredCalibration stored;
  if (!root["covariance"] && !root["transformation"]) {
    throw HandEyeError(ErrorCode::MissingKey,
                       "not a calibration: neither a handeye_covariance result (`covariance`) nor easy_handeye's "
                       "(`transformation`)",
                       top.str(), "give the file /calibrate or `handeye solve --output` wrote, or easy_handeye's YAML");
  }
  // Ours has `covariance` (and easy_handeye's `transformation` block too); easy_handeye's has only the latter.
  if (root["covariance"]) {
    const CalibrationFile file = read_result_node(root, top);
    stored.setup = file.context.setup;
    stored.parent = file.context.parent;
    stored.child = file.context.child;
    stored.T_parent_camera = file.T_parent_camera;
    stored.has_covariance = true;
    stored.format = "handeye_covariance";
    return stored;
  }
  stored.format = "easy_handeye";
  const std::string hint = "easy_handeye's `transformation` is {x, y, z, qx, qy, qz, qw} in m";
  const YAML::Node transformation = root["transformation"];
  const Location at = top / "transformation";
  const auto number = [&](const char* key) {
    return as_finite(require(transformation, key, at, hint), at / key, std::string("NaN or Inf in `") + key + "`", hint);
  };
  const Eigen::Quaterniond q(number("qw"), number("qx"), number("qy"), number("qz"));
  const Vector3d t(number("x"), number("y"), number("z"));
  stored.T_parent_camera.pose =
      se3::make_pose(checked_unit_quaternion(q, (at / "qx..qw").str()).toRotationMatrix(), t);
  // The frames: under `parameters`, or at the top level in easy_handeye's older files.
  const bool nested = root["parameters"] && root["parameters"].IsMap();
  const YAML::Node parameters = nested ? root["parameters"] : root;
  const Location where = nested ? top / "parameters" : top;
  const auto text_of = [&](const char* key) {
    const YAML::Node node = parameters[key];
    return node && !node.IsNull() ? as_text(node, where / key) : std::string();
  };
  const YAML::Node eye_on_hand = parameters["eye_on_hand"];
  if (!eye_on_hand || !eye_on_hand.IsScalar()) {
    throw HandEyeError(ErrorCode::MissingKey, "an easy_handeye calibration without `eye_on_hand: true|false`",
                       where.str(), "add `eye_on_hand: true` (camera on the robot) or `false` under `parameters`");
  }
  bool on_hand = false;
  if (!YAML::convert<bool>::decode(eye_on_hand, on_hand)) {
    throw HandEyeError(ErrorCode::MalformedFile, "`eye_on_hand` must be true or false, not `" + eye_on_hand.Scalar() + "`",
                       (where / "eye_on_hand").str(), "write `eye_on_hand: true` or `eye_on_hand: false`");
  }
  stored.setup = setup_from_eye_on_hand(on_hand);
  stored.parent = text_of(on_hand ? "robot_effector_frame" : "robot_base_frame");
  stored.child = text_of("tracking_base_frame");
  return stored;
}

StoredCalibration read_stored_calibration(const std::string& path) {
  const std::string text = read_file(path);
  try {
    return parse_stored_calibration(text, path);
  } catch (const YAML::Exception& e) {  // a shape the readers did not foresee: still a named error, never a crash
    throw HandEyeError(ErrorCode::MalformedFile, std::string("unexpected YAML structure: ") + e.what(), path,
                       "compare the file with one /calibrate wrote (docs/file_formats.md)");
  }
}

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

Target parse_target(const std::string& text, const std::string& source) {
  const YAML::Node root = load(text, source);
  const Location top{source, ""};
  const std::string kinds = "chessboard, charuco, aruco, aruco_board or apriltag";
  if (root.IsMap() && root["tags"] && !root["type"]) return make_target(parse_tag_layout(text, source));
  const std::string type = as_text(require(root, "type", top, "write `type: " + kinds + "` (docs/targets.md)"),
                                   top / "type");
  const auto length = [&](const char* key, const std::string& hint) {
    const double v = as_double(require(root, key, top, hint), top / key);
    if (!(v > 0.0 && v < 10.0)) {
      throw HandEyeError(ErrorCode::InvalidLayout, std::string("`") + key + "` must be a length in m, above 0 and below 10",
                         (top / key).str(), hint);
    }
    return v;
  };
  const auto pair = [&](const char* key, const std::string& what, const std::string& hint) {
    const YAML::Node node = require(root, key, top, hint);
    if (!node.IsSequence() || node.size() != 2) {
      throw HandEyeError(ErrorCode::WrongLength, "`" + std::string(key) + "` must be [columns, rows] (" + what + ")",
                         (top / key).str(), hint);
    }
    return std::array<int, 2>{as_integer(node[0], (top / key)[0], 1, 1000, what),
                              as_integer(node[1], (top / key)[1], 1, 1000, what)};
  };
  const auto name = [&](const char* key, const std::string& hint) { return as_text(require(root, key, top, hint), top / key); };
  const auto id = [&](const char* key, const std::string& hint) {
    return as_integer(require(root, key, top, hint), top / key, 0, 1e6, "the marker id");
  };
  if (type == "chessboard") {
    const std::string hint = "e.g. {type: chessboard, inner_corners: [9, 6], square: 0.0236}";
    const auto corners = pair("inner_corners", "inner corners", hint);
    return make_target(ChessboardTarget{corners[0], corners[1], length("square", hint)});
  }
  if (type == "charuco") {
    const std::string hint = "e.g. {type: charuco, squares: [7, 5], square: 0.036, marker: 0.018, dictionary: DICT_6X6_250}";
    const auto squares = pair("squares", "squares", hint);
    return make_target(CharucoTarget{squares[0], squares[1], length("square", hint), length("marker", hint),
                                     name("dictionary", hint)});
  }
  if (type == "aruco") {
    const std::string hint = "e.g. {type: aruco, dictionary: DICT_4X4_50, id: 7, marker: 0.05}";
    const std::string dictionary = name("dictionary", hint);
    return make_target(single_tag_layout(id("id", hint), length("marker", hint), dictionary));
  }
  if (type == "aruco_board") {
    const std::string hint =
        "e.g. {type: aruco_board, dictionary: DICT_4X4_50, markers: [4, 3], marker: 0.06, separation: 0.015}";
    const std::string dictionary = name("dictionary", hint);
    const auto markers = pair("markers", "markers", hint);
    const double separation = as_double(require(root, "separation", top, hint), top / "separation");
    if (!(separation >= 0.0 && separation < 10.0)) {
      throw HandEyeError(ErrorCode::InvalidLayout, "`separation` must be a length in m, 0 or more", (top / "separation").str(), hint);
    }
    const int first = root["first_id"] ? as_integer(root["first_id"], top / "first_id", 0, 1e6, "the first id") : 0;
    return make_target(aruco_grid_layout(dictionary, markers[0], markers[1], length("marker", hint), separation, first));
  }
  if (type == "apriltag") {
    const std::string hint = "e.g. {type: apriltag, family: tag36h11, id: 10, size: 0.048}";
    const std::string family = root["family"] ? as_text(root["family"], top / "family") : "tag36h11";
    return make_target(single_tag_layout(id("id", hint), length("size", hint), family));
  }
  throw HandEyeError(ErrorCode::InvalidLayout, "unknown target type `" + type + "`", (top / "type").str(),
                     "use " + kinds);
}

Target read_target(const std::string& path) { return parse_target(read_file(path), path); }

// ---------------------------------------------------------------- camera_info

Eigen::Vector4d intrinsics_sigma(const YAML::Node& node, const Location& at) {
  const auto values = as_numbers<4>(node, at, "the 1 sigma of fx, fy, cx, cy in px");
  const Eigen::Vector4d sigma(values[0], values[1], values[2], values[3]);
  if (!(sigma.array() >= 0.0).all()) {
    throw HandEyeError(ErrorCode::MalformedFile, "intrinsics_sigma holds a negative sigma", at.str(),
                       "give the 1 sigma of fx, fy, cx, cy in px, each >= 0 (e.g. from handeye images --refine-intrinsics)");
  }
  return sigma;
}

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

// ---------------------------------------------------------------- session config

void read_session_config(const std::string& path, SessionConfig& config) {
  const YAML::Node root = load(read_file(path), path);
  const Location top{path, ""};
  if (!root.IsNull() && !root.IsMap()) {
    throw HandEyeError(ErrorCode::MalformedFile, "expected `setting: value` lines", path,
                       "see config/calibration_defaults.yaml for the settings and their form");
  }
  std::set<std::string> known;
  for_each_setting(config, [&](const char* key, auto& member, double scale) {
    known.insert(key);
    const YAML::Node node = root[key];
    if (!node || node.IsNull()) return;
    using T = std::decay_t<decltype(member)>;
    try {
      if constexpr (std::is_same_v<T, double>) {
        member = as_double(node, top / key) * scale;
      } else if constexpr (std::is_same_v<T, Setup>) {
        member = setup_from_eye_on_hand(node.as<bool>());
      } else {
        member = node.as<T>();
      }
    } catch (const YAML::Exception&) {
      throw HandEyeError(ErrorCode::MalformedFile, std::string("`") + key + "` has the wrong type", (top / key).str(),
                         "see config/calibration_defaults.yaml for the expected value");
    }
  });
  for (const auto& entry : root) {
    const std::string key = as_text(entry.first, top);
    if (!known.count(key)) {
      throw HandEyeError(ErrorCode::MalformedFile, "unknown setting `" + key + "`", path,
                         "use the node's parameter names (config/calibration_defaults.yaml, launch/calibrate.launch)");
    }
  }
}

// ---------------------------------------------------------------- files

std::string expand_home(const std::string& path) {
  if (path.rfind("~/", 0) != 0) return path;
  const char* home = std::getenv("HOME");
  return std::string(home ? home : ".") + path.substr(1);
}

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    throw HandEyeError(ErrorCode::IoError, std::string("cannot open: ") + std::strerror(errno), path,
                       "check the path and the permissions");
  }
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

void write_file_atomically(const std::string& path, const std::string& content) {
  namespace fs = std::filesystem;
  const fs::path target(path);
  std::error_code ec;
  if (target.has_parent_path()) fs::create_directories(target.parent_path(), ec);
  // Unique per process and per call: two threads writing the same file never share a temporary.
  static std::atomic<unsigned> calls{0};
  const std::string temporary = path + ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(calls++);
  const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  bool ok = fd >= 0;
  for (std::size_t written = 0; ok && written < content.size();) {
    const ssize_t n = ::write(fd, content.data() + written, content.size() - written);
    if (n < 0 && errno == EINTR) continue;
    ok = n > 0;
    if (ok) written += static_cast<std::size_t>(n);
  }
  ok = ok && ::fsync(fd) == 0;  // the data is on disk before the name points at it
  if (fd >= 0) ok = (::close(fd) == 0) && ok;
  if (!ok) {
    const std::string reason = std::strerror(errno);
    std::remove(temporary.c_str());
    throw HandEyeError(ErrorCode::IoError, "cannot write: " + reason, path,
                       "check that the directory is writable and the disk is not full");
  }
  if (std::rename(temporary.c_str(), path.c_str()) != 0) {
    const std::string reason = std::strerror(errno);
    std::remove(temporary.c_str());
    throw HandEyeError(ErrorCode::IoError, "cannot rename the temporary file into place: " + reason, path,
                       "check the permissions of the target directory");
  }
}

}  // namespace io
}  // namespace handeye
