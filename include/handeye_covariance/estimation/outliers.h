// Outlier rejection for pose samples: wrong detections (a flipped tag pose, a
// detection paired with the wrong robot pose) must not corrupt X.
//
//  1. Consensus, before any X exists. For a pair of samples, A X = X B
//     demands that A and B rotate by the same angle and have the same screw
//     pitch (omega . t), whatever X is (Chen's screw congruence). Each sample
//     is compared with every other, or in a session of more than
//     `consensus_partners` + 1 samples with that many others spread over it (the
//     cost grows with n, not n^2). A sample that disagrees with most of those it
//     is compared with is rejected. Scales are robust (the differences' robust
//     sigma over the pairs compared), with floors for noise-free input.
//  2. Residual gating after the solve. Each sample's pattern pose is compared
//     with what X, its robot pose and the pattern's mean pose predict (eq.
//     64-65). Its Mahalanobis distance is taken under the predicted covariance
//     of that residual: camera noise, robot noise mapped through the chain, and
//     the estimation error of X and of the mean pose. It must stay below the
//     chi2(6) 0.9999 quantile, scaled up by (median distance / chi2(6) median)
//     when that exceeds 1 (a detector's decoupled covariance can understate a
//     correlated truth). The worst offender is dropped and X re-solved, one at
//     a time.
// At most `max_rejected_fraction` of the samples are rejected; beyond that the
// session is refused as inconsistent.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "handeye_covariance/core/units.h"
#include "handeye_covariance/estimation/joint_estimator.h"

namespace handeye {

struct OutlierOptions {
  double consensus_sigmas = 6.0;            // a pair disagrees beyond this many robust sigmas
  double min_angle_gate = radians(0.1);  // rad: floors of the gates (noise-free input)
  double min_pitch_gate = 0.2e-3;           // m
  double min_pitch_angle = radians(5.0);  // pitch is compared only for rotations beyond this
  double disagreeing_share = 0.5;           // a sample disagreeing with more than this share of others is rejected
  int consensus_partners = 60;              // each sample is compared with at most this many others (even, >= 4)
  double residual_gate = 27.86;             // chi2(6) 0.9999 quantile
  double max_rejected_fraction = 0.3;
};

/// How one sample fits a calibration: its pattern pose against what X, its robot
/// pose and the pattern's mean pose predict (eq. 64-65), and how many sigmas that
/// is under the residual's predicted covariance (stage 2 above judges by it).
struct SampleFit {
  Vector6d error = Vector6d::Zero();  // camera frame, ROS order (m, rad)
  double translation = 0.0;           // m, |error.head<3>()|
  double rotation = 0.0;              // rad, |error.tail<3>()|
  double sigmas = 0.0;                // Mahalanobis length (6 dof); 0 for a noise-free residual or a zero-noise axis
};

/// Every sample of `samples` against `calibration`, solved from `samples` without
/// the ones `calibration.rejected` names: the rejected are judged against the rest.
std::vector<SampleFit> sample_fits(const SampleSet& samples, const Calibration& calibration);

/// What solve_robust said of sample `index`, or nullptr when it was kept.
const Calibration::Rejected* rejection_of(const Calibration& calibration, int index);

/// The factor on chi2(6) thresholds for samples whose squared Mahalanobis
/// distances are `squared_distances`: their median over chi2(6)'s median,
/// at least 1 (1 for none). A detector's decoupled covariance can understate a
/// correlated truth; scaled so, samples are judged against each other (stage 2).
double residual_scale(std::vector<double> squared_distances);

/// The pairs (i < j) stage 1 compares among n samples: all of them when each sample has at
/// most `partners` others; else each sample i with the samples i + d (mod n) for `partners` / 2
/// offsets d spread evenly over [1, n / 2] (as i and as i + d), so each is compared with
/// `partners` others near and far along the session (`partners` - 1 when n is even: the
/// offset n / 2 pairs a sample once). `partners` even and >= 4.
std::vector<std::pair<int, int>> consensus_pairs(int n, int partners);

/// Stage 1: the samples whose motions to more than `disagreeing_share` of the others
/// they are compared with break screw congruence (rotation angle or pitch beyond the
/// robust gates). Each rejected entry says how many it was compared with.
std::vector<Calibration::Rejected> consensus(const SampleSet& samples, const OutlierOptions& options);

/// Each sample of `evaluated` against X and the mean pattern pose of `fitted`, the
/// samples `c` was solved from, under the residual's predicted covariance (camera and
/// robot noise, and the shared error of X and of the pattern's mean pose, eq. 64-65).
std::vector<SampleFit> fits_against(const SampleSet& fitted, const Calibration& c, const SampleSet& evaluated);

/// `samples` without the indices `dropped`.
SampleSet without(const SampleSet& samples, const std::vector<int>& dropped);

/// The samples without those `calibration.rejected` names.
SampleSet without_rejected(const SampleSet& samples, const Calibration& calibration);

}  // namespace handeye
