#include "handeye_covariance/simulation/simulation.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <algorithm>
#include <random>

namespace handeye {

using Eigen::Isometry3d;
using Eigen::Matrix3d;
using Eigen::Vector3d;

Vector3d sample_gaussian(Rng& rng, const Matrix3d& covariance) {
  // Eigen-decomposition rather than Cholesky so singular (e.g. zero) noise works.
  const Eigen::SelfAdjointEigenSolver<Matrix3d> eig(covariance);
  std::normal_distribution<double> normal(0.0, 1.0);
  // Draws in a fixed order (z, y, x). Three draws as constructor arguments are
  // unsequenced: gcc drew them right to left and clang left to right, so seeded
  // data differed between compilers. This keeps gcc's order (and every figure).
  const double z2 = normal(rng), z1 = normal(rng), z0 = normal(rng);
  const Vector3d z(z0, z1, z2);
  const Vector3d sd = eig.eigenvalues().cwiseMax(0.0).cwiseSqrt();
  return eig.eigenvectors() * sd.cwiseProduct(z);
}

Isometry3d random_pose(Rng& rng, double translation_extent) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double u1 = unit(rng), u2 = 2.0 * M_PI * unit(rng), u3 = 2.0 * M_PI * unit(rng);
  const Eigen::Quaterniond q(std::sqrt(u1) * std::cos(u3), std::sqrt(1.0 - u1) * std::sin(u2),
                             std::sqrt(1.0 - u1) * std::cos(u2), std::sqrt(u1) * std::sin(u3));
  std::uniform_real_distribution<double> box(-translation_extent, translation_extent);
  const double z = box(rng), y = box(rng), x = box(rng);  // a fixed order; see sample_gaussian
  return se3::make_pose(q.toRotationMatrix(), Vector3d(x, y, z));
}

Isometry3d perturb(Rng& rng, const Isometry3d& pose, const PoseNoise& noise) {
  const Vector3d xi_R = sample_gaussian(rng, noise.rotation);
  Vector3d xi_t;
  if (!noise.has_cross_block()) {
    xi_t = sample_gaussian(rng, noise.translation);
  } else {
    // xi_t given xi_R (Gaussian conditioning): the same three draws, and the pair
    // has the full 6x6, cross block included.
    const Matrix3d gain = noise.translation_rotation * Eigen::CompleteOrthogonalDecomposition<Matrix3d>(noise.rotation).pseudoInverse();
    xi_t = gain * xi_R + sample_gaussian(rng, noise.translation - gain * noise.translation_rotation.transpose());
  }
  return se3::make_pose(so3::exp(xi_R) * pose.linear(), pose.translation() + xi_t);
}

MeasurementNoise paper_noise(double lambda) {
  MeasurementNoise noise;
  noise.robot.rotation = lambda * Vector3d(0.5, 0.2, 0.3).asDiagonal();     // eq. (57)
  noise.camera.rotation = lambda * Vector3d(0.7, 0.2, 0.8).asDiagonal();    // eq. (58)
  noise.robot.translation = lambda * Vector3d(0.1, 0.2, 0.5).asDiagonal();  // eq. (59)
  noise.camera.translation = lambda * Vector3d(0.7, 0.8, 0.1).asDiagonal(); // eq. (60)
  return noise;
}

MotionSet simulate_motions(Rng& rng, const Isometry3d& X, int k, const MeasurementNoise& noise,
                           double translation_extent) {
  MotionSet set;
  set.noise = noise;
  const Isometry3d X_inverse = X.inverse();
  for (int i = 0; i < k; ++i) {
    const Isometry3d A = random_pose(rng, translation_extent);
    MotionPair pair;
    pair.A = perturb(rng, A, noise.robot);
    pair.B = perturb(rng, X_inverse * A * X, noise.camera);
    set.motions.push_back(pair);
  }
  return set;
}

Isometry3d typical_X(Setup setup) {
  if (setup == Setup::EyeInHand) {
    // Camera 10 cm off the flange, looking roughly along the tool axis.
    return se3::make_pose(so3::exp(Vector3d(0.05, -0.08, 1.52)), Vector3d(0.035, -0.062, 0.101));
  }
  // Camera 1.2 m from the base, looking down at the workspace.
  return se3::make_pose(so3::exp(Vector3d(2.6, 0.4, -0.3)), Vector3d(0.85, 0.42, 1.21));
}

SimulatedSession simulate_session(Rng& rng, Setup setup, const Isometry3d& X, int n,
                                  const MeasurementNoise& noise, const ViewpointOptions& views) {
  SimulatedSession session;
  session.X = X;
  session.samples.rig = {setup, {"base_link", "tool0", "camera_optical_frame", "tag_0"}};
  session.samples.noise = noise;
  if (setup == Setup::EyeInHand) {
    // Pattern on the table 0.6 m in front of the robot.
    session.T_world_pattern =
        se3::make_pose(so3::exp(Vector3d(0.0, 0.0, 0.3)), Vector3d(0.6, 0.1, 0.02));
  } else {
    // Pattern plate 8 cm off the flange.
    session.T_world_pattern = se3::make_pose(so3::exp(Vector3d(0.1, 0.2, -0.4)), Vector3d(0.01, 0.02, 0.08));
  }
  const Isometry3d& Y = session.T_world_pattern;
  for (int i = 0; i < n; ++i) {
    const Isometry3d P = random_view(rng, views);  // T_camera_pattern
    const Isometry3d E = session.samples.rig.effector_for_view(X, Y, P);
    PoseSample sample;
    sample.T_base_effector = perturb(rng, E, noise.robot);
    sample.T_camera_pattern = perturb(rng, P, noise.camera);
    sample.stamp = 2.0 * i;
    session.samples.samples.push_back(sample);
  }
  return session;
}

Isometry3d RigTrajectory::effector_at(double t) const {
  const double period = pause + move;
  const double elapsed = std::max(0.0, t);
  const std::size_t i = static_cast<std::size_t>(elapsed / period);
  if (i + 1 >= poses.size()) return poses.back();
  const double u = std::clamp((elapsed - static_cast<double>(i) * period - pause) / move, 0.0, 1.0);
  const double s = u * u * (3.0 - 2.0 * u);  // smoothstep: no jerk at the pauses
  const Eigen::Quaterniond q0(poses[i].linear()), q1(poses[i + 1].linear());
  return se3::make_pose(q0.slerp(s, q1).toRotationMatrix(), (1.0 - s) * poses[i].translation() + s * poses[i + 1].translation());
}

Isometry3d RigTrajectory::pattern_at(double t) const {
  return rig.predicted_view(effector_at(t), X, T_world_pattern);
}

RigTrajectory make_rig_trajectory(Rng& rng, Setup setup, const Isometry3d& X, int n, double pause, double move,
                                  const ViewpointOptions& views) {
  const SimulatedSession session = simulate_session(rng, setup, X, n, MeasurementNoise{}, views);
  RigTrajectory trajectory;
  trajectory.rig = session.samples.rig;
  trajectory.X = X;
  trajectory.T_world_pattern = session.T_world_pattern;
  for (const PoseSample& sample : session.samples.samples) trajectory.poses.push_back(sample.T_base_effector);
  trajectory.pause = pause;
  trajectory.move = move;
  return trajectory;
}

void add_shared_robot_error(Rng& rng, SampleSet& samples, double translation_sigma, double rotation_sigma) {
  const int n = static_cast<int>(samples.samples.size());
  if (n < 2) return;
  std::vector<double> distances;
  Eigen::MatrixXd K(n, n);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const double d = (samples.samples[static_cast<std::size_t>(i)].T_base_effector.translation() -
                        samples.samples[static_cast<std::size_t>(j)].T_base_effector.translation()).norm();
      K(i, j) = d;
      if (j > i) distances.push_back(d);
    }
  }
  std::nth_element(distances.begin(), distances.begin() + static_cast<long>(distances.size() / 2), distances.end());
  const double l = distances[distances.size() / 2];
  K = (-K.array().square() / (2.0 * l * l)).exp().matrix() + 1e-9 * Eigen::MatrixXd::Identity(n, n);
  const Eigen::MatrixXd lower = Eigen::LLT<Eigen::MatrixXd>(K).matrixL();
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::MatrixXd z(n, 6);
  for (int i = 0; i < n; ++i) {
    for (int a = 0; a < 6; ++a) z(i, a) = normal(rng);
  }
  const Eigen::MatrixXd g = lower * z;
  for (int i = 0; i < n; ++i) {
    PoseSample& sample = samples.samples[static_cast<std::size_t>(i)];
    const Eigen::Vector3d t = translation_sigma * g.row(i).head<3>().transpose();
    const Eigen::Vector3d w = rotation_sigma * g.row(i).tail<3>().transpose();
    sample.T_base_effector = se3::make_pose(so3::exp(w) * sample.T_base_effector.linear(), sample.T_base_effector.translation() + t);
  }
}

}  // namespace handeye
