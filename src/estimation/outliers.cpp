#include "handeye_covariance/estimation/outliers.h"

#include <algorithm>
#include <numeric>
#include <stdexcept>
#include <string>
#include <utility>

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/core/statistics.h"
#include "handeye_covariance/estimation/noise_estimation.h"

namespace handeye {

using Eigen::Isometry3d;
using Eigen::Vector3d;

namespace {

struct PairCheck {
  int i = 0, j = 0;
  double angle_difference = 0.0;           // rad
  std::optional<double> pitch_difference;  // m, when both rotate enough for a stable axis
};

}  // namespace

std::vector<std::pair<int, int>> consensus_pairs(int n, int partners) {
  if (partners < 4 || partners % 2 != 0) {
    throw std::invalid_argument("OutlierOptions::consensus_partners must be even and at least 4, got " +
                                std::to_string(partners));
  }
  std::vector<std::pair<int, int>> pairs;
  if (n - 1 <= partners) {
    pairs.reserve(static_cast<std::size_t>(n) * (n - 1) / 2);
    for (int i = 0; i < n; ++i) {
      for (int j = i + 1; j < n; ++j) pairs.emplace_back(i, j);
    }
    return pairs;
  }
  const int offsets = partners / 2, widest = n / 2;  // widest > offsets: n >= partners + 2
  pairs.reserve(static_cast<std::size_t>(n) * offsets);
  for (int m = 0; m < offsets; ++m) {
    const int d = 1 + static_cast<int>(static_cast<long long>(m) * (widest - 1) / (offsets - 1));
    for (int i = 0; i < n; ++i) {
      const int j = (i + d) % n;
      if (2 * d == n && j < i) continue;  // i + n/2 pairs with i: taken once
      pairs.emplace_back(std::min(i, j), std::max(i, j));
    }
  }
  return pairs;
}

std::vector<Calibration::Rejected> consensus(const SampleSet& samples, const OutlierOptions& o) {
  const int n = static_cast<int>(samples.samples.size());
  const std::vector<std::pair<int, int>> compared = consensus_pairs(n, o.consensus_partners);
  std::vector<PairCheck> pairs;
  pairs.reserve(compared.size());
  std::vector<double> angles, pitches;
  for (const auto& [i, j] : compared) {
    const MotionPair m = motion_between(samples.rig, samples.samples[i], samples.samples[j]);
    const Eigen::AngleAxisd a(m.A.linear()), b(m.B.linear());
    PairCheck c{i, j, std::abs(a.angle() - b.angle()), std::nullopt};
    if (std::min(a.angle(), b.angle()) > o.min_pitch_angle) {
      c.pitch_difference = std::abs(a.axis().dot(m.A.translation()) - b.axis().dot(m.B.translation()));
      pitches.push_back(*c.pitch_difference);
    }
    angles.push_back(c.angle_difference);
    pairs.push_back(c);
  }
  const double angle_gate = std::max(o.min_angle_gate, o.consensus_sigmas * robust_sigma(angles));
  const double pitch_gate = std::max(o.min_pitch_gate, o.consensus_sigmas * robust_sigma(pitches));
  std::vector<int> disagreements(n, 0), checks(n, 0);
  for (const PairCheck& c : pairs) {
    const bool bad = c.angle_difference > angle_gate || (c.pitch_difference && *c.pitch_difference > pitch_gate);
    for (int s : {c.i, c.j}) {
      ++checks[s];
      disagreements[s] += bad ? 1 : 0;
    }
  }
  std::vector<Calibration::Rejected> rejected;
  for (int s = 0; s < n; ++s) {
    const double share = checks[s] ? static_cast<double>(disagreements[s]) / checks[s] : 0.0;
    if (share > o.disagreeing_share) {
      Calibration::Rejected r;
      r.index = s, r.why = Calibration::Rejected::Why::MotionsBreakAXXB;
      r.disagreeing = disagreements[s], r.compared = checks[s], r.angle_gate = angle_gate, r.pitch_gate = pitch_gate;
      rejected.push_back(r);
    }
  }
  return rejected;
}

SampleSet without(const SampleSet& samples, const std::vector<int>& dropped) {
  SampleSet kept = samples;
  kept.samples.clear();
  for (int i = 0; i < static_cast<int>(samples.samples.size()); ++i) {
    if (std::find(dropped.begin(), dropped.end(), i) == dropped.end()) kept.samples.push_back(samples.samples[i]);
  }
  return kept;
}

std::vector<SampleFit> fits_against(const SampleSet& fitted, const Calibration& c, const SampleSet& evaluated) {
  const Rig& rig = fitted.rig;
  const Isometry3d& X = c.T_parent_camera;
  const Isometry3d pattern = pattern_pose(fitted, X);
  const double m = static_cast<double>(fitted.samples.size());
  Matrix6d dY_dX = Matrix6d::Zero(), Y_noise = Matrix6d::Zero();
  for (const PoseSample& s : fitted.samples) {
    const Isometry3d V_inverse = rig.robot_link(s.T_base_effector).inverse();
    const MeasurementNoise& noise = s.noise ? *s.noise : c.noise;
    dY_dX += compose_jacobian_right(V_inverse) * compose_jacobian_left(X, s.T_camera_pattern) / m;
    const Matrix6d G = compose_jacobian_right(V_inverse * X) / m;
    Y_noise += G * noise.camera.as_pose_covariance() * G.transpose();
  }
  std::vector<SampleFit> fits;
  fits.reserve(evaluated.samples.size());
  for (const PoseSample& s : evaluated.samples) {
    const MeasurementNoise& noise = s.noise ? *s.noise : c.noise;
    const SampleResidual r = sample_residual(rig, s, X, pattern);
    SampleFit& fit = fits.emplace_back();
    fit.error = r.error;
    fit.translation = r.error.head<3>().norm();
    fit.rotation = r.error.tail<3>().norm();
    if (r.error.norm() < 1e-9) continue;  // noise-free input: nothing to judge
    const Isometry3d V = rig.robot_link(s.T_base_effector);
    const Matrix6d dP_dY = compose_jacobian_right(X.inverse() * V);
    const Matrix6d dP_dX = compose_jacobian_left(X.inverse(), V * pattern) * inverse_jacobian(X) + dP_dY * dY_dX;
    const Matrix6d S = noise.camera.as_pose_covariance() +
                       r.d_effector * noise.robot.as_pose_covariance() * r.d_effector.transpose() +
                       dP_dX * c.pose_covariance * dP_dX.transpose() + dP_dY * Y_noise * dP_dY.transpose();
    const Eigen::LDLT<Matrix6d> ldlt(S);
    if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().array() > 0.0).all()) continue;  // a zero-noise axis
    fit.sigmas = std::sqrt(std::max(0.0, r.error.dot(ldlt.solve(r.error))));
  }
  return fits;
}

SampleSet without_rejected(const SampleSet& samples, const Calibration& calibration) {
  std::vector<int> dropped;
  for (const auto& r : calibration.rejected) dropped.push_back(r.index);
  return without(samples, dropped);
}

const Calibration::Rejected* rejection_of(const Calibration& calibration, int index) {
  for (const Calibration::Rejected& r : calibration.rejected) {
    if (r.index == index) return &r;
  }
  return nullptr;
}

double residual_scale(std::vector<double> squared_distances) {
  if (squared_distances.empty()) return 1.0;
  return std::max(1.0, median(std::move(squared_distances)) / kChi2SixDofMedian);
}

std::vector<SampleFit> sample_fits(const SampleSet& samples, const Calibration& calibration) {
  return fits_against(without_rejected(samples, calibration), calibration, samples);
}

}  // namespace handeye
