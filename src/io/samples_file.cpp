// Samples and motions files, candidate poses, noise files, suggestions and noise
// estimates (samples_file.h).
#include "handeye_covariance/io/samples_file.h"

#include <algorithm>
#include <cmath>
#include <memory>

#include "handeye_covariance/core/units.h"
#include "handeye_covariance/io/files.h"
#include "yaml_primitives.h"

namespace handeye {
namespace io {

using namespace detail;  // the shared readers and writers (yaml_primitives.h)
using Eigen::Isometry3d;
using Eigen::Matrix3d;
using Eigen::Vector3d;

namespace {

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
  out << YAML::Key << "current_object_sigma_mm" << YAML::Value << millimetres(suggestion.current_object_sigma);
  const auto emit_scored = [&](const ScoredPose& p) {
    out << YAML::BeginMap;
    emit_pose(out, p.T_base_effector);
    out << YAML::Key << "object_sigma_mm" << YAML::Value << millimetres(p.object_sigma);
    out << YAML::Key << "score" << YAML::Value << p.score;
    out << YAML::EndMap;
  };
  out << YAML::Key << "suggestions" << YAML::Value << YAML::BeginSeq;  // T_base_effector, best first
  for (int i = 0; i < count && i < static_cast<int>(suggestion.ranked.size()); ++i) emit_scored(suggestion.ranked[i]);
  out << YAML::EndSeq;
  out << YAML::Key << "plan" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "target_object_sigma_mm" << YAML::Value << millimetres(target_object_sigma);
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
  sigmas("pattern_sigma_mm", estimate.noise.camera.translation, kMillimetresPerMetre);
  sigmas("pattern_sigma_deg", estimate.noise.camera.rotation, kDegreesPerRadian);
  sigmas("effector_sigma_mm", estimate.noise.robot.translation, kMillimetresPerMetre);
  sigmas("effector_sigma_deg", estimate.noise.robot.rotation, kDegreesPerRadian);
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

}  // namespace io
}  // namespace handeye
