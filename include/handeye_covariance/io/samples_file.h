// Samples and motions files and what is written beside them: candidate poses,
// noise files, suggestions, noise estimates (yaml-cpp; no ROS). See docs/file_formats.md.
//
//  samples file:  setup, frames?, noise? {effector, pattern}, samples: [{effector, pattern, stamp?, noise?}]
//  motions file:  setup?, noise? {A, B}, motions: [{A, B, noise?}]
//
// Poses are {translation: [x, y, z], rotation: [qx, qy, qz, qw]}; covariances are
// 9 numbers row-major (rad^2, m^2). Readers throw HandEyeError naming the field.
#pragma once

#include <string>
#include <variant>
#include <vector>

#include <Eigen/Geometry>

#include "handeye_covariance/core/measurements.h"
#include "handeye_covariance/estimation/next_best_pose.h"
#include "handeye_covariance/estimation/noise_estimation.h"

namespace handeye {
namespace io {

/// Parse from text; `source` names the file in error messages.
SampleSet parse_samples(const std::string& text, const std::string& source);
MotionSet parse_motions(const std::string& text, const std::string& source);

SampleSet read_samples(const std::string& path);

/// A file whose `noise:` block is a samples file's ({effector: ..., pattern: ...}),
/// as the node's ~noise_config. Throws MissingKey when there is no such block.
MeasurementNoise read_noise_file(const std::string& path);

/// A file holding either samples or motions (told apart by its top-level key).
using Input = std::variant<SampleSet, MotionSet>;
Input read_input(const std::string& path);

std::string format_samples(const SampleSet& samples);

/// Candidate effector poses (T_base_effector) for the next-best-pose
/// suggestions: `candidates: [{translation: [x, y, z], rotation: [qx, qy, qz, qw]}, ...]`.
std::vector<Eigen::Isometry3d> parse_candidate_poses(const std::string& text, const std::string& source);
std::vector<Eigen::Isometry3d> read_candidate_poses(const std::string& path);

/// What `handeye suggest` writes: the ranked next poses and the plan to the
/// target. Its `suggestions` list has the `candidates` format's pose keys.
std::string format_suggestions(const Suggestion& suggestion, int count, const Plan& plan, double target_object_sigma,
                               const SuggestOptions& options);

/// The file `handeye noise` writes: a `noise: {effector, pattern}` block, which
/// read_noise_file, the node's ~noise_config and `solve --noise` accept, and an
/// `estimate:` block saying how it was measured (source, dof, 1 sigma per axis).
std::string format_noise_estimate(const NoiseEstimate& estimate);
std::string format_motions(const MotionSet& motions);

}  // namespace io
}  // namespace handeye
