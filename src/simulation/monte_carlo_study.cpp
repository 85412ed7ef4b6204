#include "handeye_covariance/simulation/monte_carlo_study.h"

#include <chrono>

#include "handeye_covariance/estimation/joint_estimator.h"
#include "handeye_covariance/simulation/simulation.h"

namespace handeye {

const char* to_string(Protocol protocol) {
  switch (protocol) {
    case Protocol::Paper: return "paper";
    case Protocol::Published: return "published";
    case Protocol::RotationDominated: return "rotation-dominated";
    case Protocol::PoseStream: return "pose-stream";
    case Protocol::JointEyeInHand: return "joint-eye-in-hand";
    case Protocol::JointEyeToHand: return "joint-eye-to-hand";
    case Protocol::JointEstimatedNoise: return "joint-estimated-noise";
  }
  return "unknown";
}

Protocol protocol_from_string(const std::string& name) {
  for (Protocol p : {Protocol::Paper, Protocol::Published, Protocol::RotationDominated, Protocol::PoseStream,
                     Protocol::JointEyeInHand, Protocol::JointEyeToHand, Protocol::JointEstimatedNoise}) {
    if (name == to_string(p)) return p;
  }
  throw HandEyeError(ErrorCode::MalformedFile, "unknown protocol `" + name + "`", "--protocol",
                     "use paper, published, rotation-dominated, pose-stream, joint-eye-in-hand, joint-eye-to-hand or "
                     "joint-estimated-noise");
}

bool is_joint(Protocol p) {
  return p == Protocol::JointEyeInHand || p == Protocol::JointEyeToHand || p == Protocol::JointEstimatedNoise;
}

StudyResult run_study(const StudyOptions& o) {
  Rng rng(o.seed);
  MeasurementNoise noise = paper_noise(o.lambda);
  double extent = 0.5;
  if (o.protocol == Protocol::Published) {
    noise.robot.rotation = o.lambda * Eigen::Vector3d(5, 2, 3).asDiagonal();
    noise.camera.rotation = o.lambda * Eigen::Vector3d(7, 2, 8).asDiagonal();
  } else if (o.protocol == Protocol::RotationDominated) {
    noise.robot.translation *= 1e-3;
    noise.camera.translation *= 1e-3;
    extent = 1.0;
  }
  Rng truth_rng(o.seed + 1000);
  const Eigen::Isometry3d X = random_pose(truth_rng, 0.5);

  MonteCarloAccumulator ours, per_pair, pattern, pairs;
  StudyResult result;
  double seconds = 0.0;
  for (int m = 0; m < o.M; ++m) {
    Eigen::Isometry3d truth = X;
    Calibration c;
    if (is_joint(o.protocol)) {
      const Setup setup = o.protocol == Protocol::JointEyeToHand ? Setup::EyeToHand : Setup::EyeInHand;
      SimulatedSession s = simulate_session(rng, setup, typical_X(setup), o.k + 1, noise);
      if (o.protocol == Protocol::JointEstimatedNoise) s.samples.noise.reset();
      const auto start = std::chrono::steady_clock::now();
      c = solve_joint(s.samples);
      seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      const Calibration p = solve(s.samples);
      const Vector6d error = pose_error(c.T_parent_camera, s.X), pairs_error = pose_error(p.T_parent_camera, s.X);
      ours.add(error, c.pose_covariance);
      pattern.add(pose_error(c.pattern->pose, s.T_world_pattern), c.pattern->covariance);
      pairs.add(pairs_error, p.pose_covariance);
      result.rms_translation += error.head<3>().squaredNorm() / o.M;
      result.pairs_rms_translation += pairs_error.head<3>().squaredNorm() / o.M;
      result.not_converged += c.rotation_stage.converged() ? 0 : 1;
      continue;
    }
    if (o.protocol == Protocol::PoseStream) {
      const SimulatedSession s = simulate_session(rng, o.setup, typical_X(o.setup), o.k + 1, noise);
      truth = s.X;
      const auto start = std::chrono::steady_clock::now();
      c = solve(s.samples);
      seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    } else {
      const MotionSet set = simulate_motions(rng, X, o.k, noise, extent);
      const auto start = std::chrono::steady_clock::now();
      c = solve(set);
      seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }
    const Vector6d error = pose_error(c.T_parent_camera, truth);
    ours.add(error, c.pose_covariance);
    per_pair.add(error, c.per_pair_covariance.as_pose_covariance());
    result.not_converged += (c.rotation_stage.converged() && c.translation_stage.converged()) ? 0 : 1;
  }
  result.ours = ours.summary();
  if (is_joint(o.protocol)) {
    result.pattern = pattern.summary();
    result.pairs = pairs.summary();
    result.rms_translation = std::sqrt(result.rms_translation);
    result.pairs_rms_translation = std::sqrt(result.pairs_rms_translation);
  } else {
    result.per_pair = per_pair.summary();
  }
  result.seconds_per_solve = seconds / std::max(1, o.M);
  return result;
}

}  // namespace handeye
