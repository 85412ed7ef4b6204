#include "handeye_covariance/simulation/systematic.h"

#include <Eigen/Cholesky>
#include <cmath>

#include "handeye_covariance/estimation/joint_estimator.h"

namespace handeye {

using Eigen::Isometry3d;
using Eigen::Vector3d;

SerialArm SerialArm::ur10() {
  return SerialArm({DhJoint{0.0, 0.1273, M_PI / 2, 0.0}, DhJoint{-0.612, 0.0, 0.0, 0.0}, DhJoint{-0.5723, 0.0, 0.0, 0.0},
                    DhJoint{0.0, 0.163941, M_PI / 2, 0.0}, DhJoint{0.0, 0.1157, -M_PI / 2, 0.0},
                    DhJoint{0.0, 0.0922, 0.0, 0.0}});
}

SerialArm::SerialArm(const std::array<DhJoint, 6>& joints) : joints_(joints) {
  for (std::size_t i = 0; i < joints_.size(); ++i) {
    fixed_[i] = Isometry3d::Identity();
    fixed_[i].translate(Vector3d(joints_[i].a, 0.0, joints_[i].d));
    fixed_[i].rotate(Eigen::AngleAxisd(joints_[i].alpha, Vector3d::UnitX()));
  }
}

Isometry3d SerialArm::forward(const Vector6d& q) const {
  // Each link is Rz(theta + offset) then its fixed part: one sine and cosine a joint
  // (the inverse kinematics of the simulated sessions call this millions of times).
  Isometry3d T = Isometry3d::Identity();
  for (std::size_t i = 0; i < joints_.size(); ++i) {
    const double theta = q[static_cast<Eigen::Index>(i)] + joints_[i].offset;
    const double c = std::cos(theta), s = std::sin(theta);
    const Vector3d x = T.linear().col(0), y = T.linear().col(1);
    T.linear().col(0) = c * x + s * y;  // T Rz(theta)
    T.linear().col(1) = c * y - s * x;
    T = T * fixed_[i];
  }
  return T;
}

std::optional<Vector6d> SerialArm::inverse(const Isometry3d& target) const {
  const auto error = [&](const Vector6d& q) { return pose_error(target, forward(q)); };
  // Seeds: the shoulder facing the target (and away), elbow up/down, wrist flipped;
  // then random ones from a fixed seed (the result must not depend on call order).
  std::vector<Vector6d> seeds;
  const double facing = std::atan2(target.translation().y(), target.translation().x());
  for (double q1 : {facing, facing + M_PI}) {
    for (double q2 : {-1.2, -2.0}) {
      for (double q3 : {1.5, -1.5}) {
        for (double q5 : {-M_PI / 2, M_PI / 2}) seeds.push_back((Vector6d() << q1, q2, q3, -1.5, q5, 0.0).finished());
      }
    }
  }
  Rng rng(12345);
  std::uniform_real_distribution<double> angle(-M_PI, M_PI);
  for (int i = 0; i < 32; ++i) {
    Vector6d q;
    for (int k = 0; k < 6; ++k) q[k] = angle(rng);
    seeds.push_back(q);
  }
  for (Vector6d q : seeds) {
    double lambda = 1e-3;
    Vector6d e = error(q);
    for (int iteration = 0; iteration < 100 && e.norm() > 1e-12; ++iteration) {
      Matrix6d J;
      for (int k = 0; k < 6; ++k) {
        Vector6d dq = q;
        dq[k] += 1e-7;
        J.col(k) = (e - error(dq)) / 1e-7;  // d(FK)/dq, as the error falls when FK moves towards the target
      }
      const Vector6d step = (J.transpose() * J + lambda * Matrix6d::Identity()).ldlt().solve(J.transpose() * e);
      const Vector6d next_e = error(q + step);
      if (next_e.norm() < e.norm()) {
        q += step, e = next_e, lambda = std::max(lambda * 0.3, 1e-12);
      } else {
        lambda *= 10.0;
        if (lambda > 1e6) break;
      }
    }
    if (e.norm() <= 1e-10) return q;
  }
  return std::nullopt;
}

SerialArm SerialArm::perturbed(Rng& rng, double length_sigma, double angle_sigma) const {
  std::normal_distribution<double> normal(0.0, 1.0);
  std::array<DhJoint, 6> joints = joints_;
  for (DhJoint& j : joints) {
    j.a += length_sigma * normal(rng);
    j.d += length_sigma * normal(rng);
    j.alpha += angle_sigma * normal(rng);
    j.offset += angle_sigma * normal(rng);
  }
  return SerialArm(joints);
}

namespace {

/// A camera noise draw with the tails of `errors`: the Gaussian draw of `noise`
/// times sqrt(3 / chi2_3) (Student-t, 3 dof), or times the contamination scale
/// for that share of poses.
Isometry3d perturb_detection(Rng& rng, const Isometry3d& pose, const PoseNoise& noise, const SystematicErrors& errors) {
  double scale = 1.0;
  if (errors.tails == SystematicErrors::Tails::StudentT3) {
    std::chi_squared_distribution<double> chi2(3.0);
    scale = std::sqrt(3.0 / chi2(rng));
  } else if (errors.tails == SystematicErrors::Tails::Contaminated) {
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    if (unit(rng) < errors.contaminated_share) scale = errors.contaminated_scale;
  }
  const PoseNoise scaled{scale * scale * noise.rotation, scale * scale * noise.translation,
                         scale * scale * noise.translation_rotation};
  return perturb(rng, pose, scaled);
}

}  // namespace

SimulatedSession simulate_systematic_session(Rng& rng, Setup setup, const Isometry3d& X, int n,
                                             const MeasurementNoise& noise, const SystematicErrors& errors,
                                             const SerialArm& nominal, const SerialArm& truth,
                                             const ViewpointOptions& views) {
  // The rig, Y and the views of simulate_session; then each sample through the arms.
  SimulatedSession session = simulate_session(rng, setup, X, 0, noise, views);
  const Isometry3d& Y = session.T_world_pattern;
  const Rig& rig = session.samples.rig;
  const bool kinematic = errors.dh_length_sigma > 0.0 || errors.dh_angle_sigma > 0.0;
  for (int tries = 0; static_cast<int>(session.samples.samples.size()) < n && tries < 100 * n; ++tries) {
    const Isometry3d P = random_view(rng, views);
    const Isometry3d E_true = rig.effector_for_view(X, Y, P);
    Isometry3d E_reported = E_true;
    if (kinematic) {
      const std::optional<Vector6d> q = truth.inverse(E_true);
      if (!q) continue;  // out of the arm's reach: another view
      E_reported = nominal.forward(*q);
    }
    Isometry3d detected = perturb_detection(rng, P, noise.camera, errors);
    detected.translation().z() *= 1.0 + errors.focal_error;  // depth scales with the focal length used
    PoseSample sample;
    sample.T_base_effector = perturb(rng, E_reported, noise.robot);
    sample.T_camera_pattern = detected;
    sample.stamp = 2.0 * static_cast<double>(session.samples.samples.size());
    session.samples.samples.push_back(sample);
  }
  return session;
}

PseudoTruth pseudo_truth(Rng& rng, Setup setup, const Isometry3d& X, const SystematicErrors& errors,
                         const SerialArm& nominal, const SerialArm& truth, const std::optional<MeasurementNoise>& weights,
                         int n, const ViewpointOptions& views) {
  SystematicErrors noise_free = errors;
  noise_free.tails = SystematicErrors::Tails::Gaussian;
  const SimulatedSession session =
      simulate_systematic_session(rng, setup, X, n, MeasurementNoise{}, noise_free, nominal, truth, views);
  SampleSet samples = session.samples;
  samples.noise = weights;  // absent: the systematic residuals' own noise model
  JointOptions options;
  options.robust = JointOptions::Robust::Off;
  options.estimate_missing_noise = false;  // the weights as the sessions have them
  const Calibration c = solve_joint(samples, options);
  return {c.T_parent_camera, c.pattern->pose};
}

}  // namespace handeye
