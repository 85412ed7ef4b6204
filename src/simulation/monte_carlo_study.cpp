#include "handeye_covariance/simulation/monte_carlo_study.h"

#include <chrono>

#include "handeye_covariance/simulation/simulation.h"

namespace handeye {

const char* to_string(Protocol protocol) {
  switch (protocol) {
    case Protocol::Paper: return "paper";
    case Protocol::Published: return "published";
    case Protocol::RotationDominated: return "rotation-dominated";
    case Protocol::PoseStream: return "pose-stream";
  }
  return "unknown";
}

Protocol protocol_from_string(const std::string& name) {
  for (Protocol p : {Protocol::Paper, Protocol::Published, Protocol::RotationDominated, Protocol::PoseStream}) {
    if (name == to_string(p)) return p;
  }
  throw HandEyeError(ErrorCode::MalformedFile, "unknown protocol `" + name + "`", "--protocol",
                     "use paper, published, rotation-dominated or pose-stream");
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

  MonteCarloAccumulator ours, per_pair;
  StudyResult result;
  double seconds = 0.0;
  for (int m = 0; m < o.M; ++m) {
    Eigen::Isometry3d truth = X;
    Calibration c;
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
  result.per_pair = per_pair.summary();
  result.seconds_per_solve = seconds / std::max(1, o.M);
  return result;
}

}  // namespace handeye
