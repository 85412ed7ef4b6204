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
};
const char* to_string(Protocol protocol);
/// paper | published | rotation-dominated | pose-stream; throws HandEyeError otherwise.
Protocol protocol_from_string(const std::string& name);

struct StudyOptions {
  Protocol protocol = Protocol::Paper;
  double lambda = 1e-4;
  int k = 30;      // motions per dataset
  int M = 2000;    // datasets
  unsigned seed = 1;
  Setup setup = Setup::EyeInHand;  // PoseStream only
};

struct StudyResult {
  MonteCarloSummary ours;      // the package's covariance
  MonteCarloSummary per_pair;  // eq. (35)/(56) as printed
  int not_converged = 0;
  double seconds_per_solve = 0.0;  // solve + covariance, data generation excluded
};

StudyResult run_study(const StudyOptions& options);

}  // namespace handeye
