// The noise sections of a calibration: what the joint fit's noise estimation
// (noise_estimation.h, joint_estimator.h) found and used, as the result file, the node
// and the summary carry it. Fields described once (core/fields.h).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "handeye_covariance/core/fields.h"
#include "handeye_covariance/core/lie.h"

namespace handeye {

/// Joint: each noise number the residuals estimated (joint_estimator.h).
struct NoiseComponent {
  std::string name;      // e.g. "camera z", "robot rotation", "stated camera noise scale"
  std::string unit;      // "m", "rad" (value is a sigma) or "" (a scale of variances)
  double value = 0.0;    // sigma (m, rad) or the scale
  double sigma = 0.0;    // 1 sigma of that value, from the residuals (0 when at its bound)
  bool supported = true; // false: the residuals do not support it, held at 0 (or its lowest value)
  template <class Self, class Visit>
  static void fields(Self& s, Visit&& visit) {
    visit("name", s.name);
    visit("value", s.value);
    visit("sigma", s.sigma);
    visit("unit", s.unit, kOptional);
    visit("supported", s.supported, kOptional);
  }
};
/// Joint, noise estimated: the noise models that were compared, by BIC (the
/// restricted log-likelihood, less half of log(6n - 12) per number), and which one
/// the covariance uses. A candidate whose score test at the chosen model promised
/// less than BIC's price of its one number is not fitted.
struct NoiseCandidate {
  std::string name;             // e.g. "camera variances, robot rotation", "+ view-following"
  int numbers = 0;              // its free noise numbers
  double score = 0.0;           // the score test that decided whether to fit it (0 for the first)
  bool fitted = false, chosen = false;
  double log_likelihood = 0.0;  // restricted, up to a constant the candidates share (fitted only)
  double bic = 0.0;             // -2 log_likelihood + numbers log(6n - 12) (fitted only)
  template <class Self, class Visit>
  static void fields(Self& s, Visit&& visit) {
    visit("name", s.name);
    visit("numbers", s.numbers);
    visit("score", s.score);
    visit("fitted", s.fitted);
    visit("chosen", s.chosen);
    visit("log_likelihood", s.log_likelihood, Only{s.fitted});
    visit("bic", s.bic, Only{s.fitted});
  }
};
/// Joint, noise estimated: how the noise model was set up and chosen, in figures and
/// codes (io::noise_model_text words it, with the components and candidates above).
/// In memory: a result file carries its words (`noise.how`), not these.
struct NoiseModelChoice {
  enum class Camera { Full, PerAxis, TranslationAndRotation };
  /// The stated noise was given and too small for the residuals: the missing part
  /// estimated; its chi2/dof.
  bool stated_too_small = false;
  double stated_chi2_per_dof = 0.0;
  Camera camera = Camera::Full;   // the camera noise's form (not stated_too_small)
  bool robot_rotation = false;    // the robot's rotation noise estimated; else the robot exact
  int residual_dof = 0;           // the samples' worth of residuals it was estimated from
  std::vector<bool> correlation;  // per noise component: a camera correlation (files name it; the words do not)
  std::vector<std::string> inseparable;  // robot numbers the camera's took in
  double bic_price = 0.0;         // BIC's price of one number, log(6n - 12)
  double inflation = 1.0, pattern_inflation = 1.0;  // for the noise estimate's own error, X's and Y's
};
/// Joint: the residual noise the covariance was computed with, for any view
/// (the samples' and new ones; joint_estimator.h residual_covariance):
///   S = camera_scale Sigma_P + camera + view_scale G(P) + D (Sigma_E + robot) D^T,
/// Sigma_P and Sigma_E the view's stated noise (its own, else the set's; zero
/// when none), D = d P_hat / d E at (X, Y). Absent (pairs): `noise` is S's.
struct ResidualNoise {
  double camera_scale = 1.0;
  Matrix6d camera = Matrix6d::Zero();  // camera frame, ROS order
  Matrix6d robot = Matrix6d::Zero();   // base (or effector) frame, as E's perturbation
  /// The view-following part, view_scale G(P) (core/view_noise.h: planar_view_covariance
  /// of view_points at the view P); 0 when the model has none.
  double view_scale = 0.0;
  std::vector<Eigen::Vector3d> view_points;
  template <class Self, class Visit>
  static void fields(Self& s, Visit&& visit) {
    visit("camera_scale", s.camera_scale);
    visit("camera", s.camera);
    visit("robot", s.robot);
    visit("view_scale", s.view_scale, kOptional);
    visit("view_points", s.view_points, kWhenSet);
  }
};
/// Joint: the check of the residuals against the noise model and what followed.
struct ResidualCheck {
  std::string test;        // e.g. "chi2 of the stated noise", "kurtosis of the Mahalanobis residuals"
  double statistic = 0.0;  // chi2/dof, or the kurtosis z score
  double bound = 0.0;      // the statistic's 99.9% bound under the model
  bool passed = true;
  template <class Self, class Visit>
  static void fields(Self& s, Visit&& visit) {
    visit("test", s.test);
    visit("statistic", s.statistic);
    visit("bound", s.bound);
    visit("passed", s.passed);
  }
};

}  // namespace handeye
