// The Monte-Carlo study of paper section IV-A, for the tests and `handeye validate`.
#pragma once

#include <string>

#include "handeye_covariance/estimation/estimator.h"
#include "handeye_covariance/simulation/monte_carlo.h"

namespace handeye {

enum class Protocol {
  Paper,              // eq. (57-60): Sigma = lambda diag(.5,.2,.3), (.7,.2,.8), (.1,.2,.5), (.7,.8,.1)
  Published,          // the T-RO version: rotations lambda diag(5,2,3) and diag(7,2,8)
  RotationDominated,  // |t_B| ~ 1 m, translation noise 1e-3 of the paper's
  PoseStream,         // noise on absolute poses (robot and camera), k+1 samples -> k motions
  // The joint estimator (joint_estimator.h) on pose streams of k+1 samples with
  // the paper's noise on the absolute poses, beside the pairs estimator on the
  // same data; X and the pattern pose Y.
  JointEyeInHand,
  JointEyeToHand,
  JointEstimatedNoise,  // eye-in-hand, no noise block: the noise estimated from the residuals
};
const char* to_string(Protocol protocol);
/// paper | published | rotation-dominated | pose-stream | joint-eye-in-hand |
/// joint-eye-to-hand | joint-estimated-noise; throws HandEyeError otherwise.
Protocol protocol_from_string(const std::string& name);

struct StudyOptions {
  Protocol protocol = Protocol::Paper;
  double lambda = 1e-4;
  int k = 30;      // motions per dataset
  int M = 2000;    // datasets
  unsigned seed = 1;
  Setup setup = Setup::EyeInHand;  // PoseStream only
};

bool is_joint(Protocol protocol);

struct StudyResult {
  MonteCarloSummary ours;      // the package's covariance (joint protocols: the joint estimator's X)
  MonteCarloSummary per_pair;  // eq. (35)/(56) as printed (pairs protocols)
  MonteCarloSummary pattern;   // joint protocols: Y
  MonteCarloSummary pairs;     // joint protocols: the pairs estimator's X on the same data
  double rms_translation = 0.0, pairs_rms_translation = 0.0;  // joint protocols: m, X against the truth
  int not_converged = 0;
  double seconds_per_solve = 0.0;  // solve + covariance, data generation excluded
};

StudyResult run_study(const StudyOptions& options);

}  // namespace handeye
