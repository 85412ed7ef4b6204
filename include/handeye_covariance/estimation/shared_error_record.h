// The shared robot error's section of a calibration: what shared_robot_error.h fitted
// and whether the session used it, as the result file, the node and the summary carry
// it. Fields described once (core/fields.h).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "handeye_covariance/core/fields.h"
#include "handeye_covariance/core/lie.h"
#include "handeye_covariance/core/pose_covariance.h"

namespace handeye {

/// A robot error shared by nearby poses (shared_robot_error.h), fitted about this
/// calibration by CalibrationSession::calibrate_checked (a joint fit without robust
/// mode, 16 to 40 kept samples; otherwise `not_fitted` says why): whether the
/// likelihood prefers it (BIC), its numbers, and X and its covariance under it.
/// `used`: the session took them (X, Y and the covariances above are the model's);
/// otherwise advice, and when `chosen` the per-view covariance understates X's by
/// what per_view_estimate_covariance says.
struct SharedErrorRecord {
  /// Empty when fitted; otherwise why not (too few or too many samples, robust
  /// mode, method corners, the fit refused): the fields below are then unset.
  std::string not_fitted;
  bool chosen = false;
  /// The calibration's X, Y and covariances are this model's (chosen, and the
  /// session uses it); the per-view model's X and its covariance are kept below.
  bool used = false;
  double bic_gain = 0.0;            // 2 (L - L0) - 4 log(6n - 12): > 0 chosen
  double length_scale = 0.0;        // m, over the effector positions
  double translation_sigma = 0.0;   // m, per axis, base frame
  double rotation_sigma = 0.0;      // rad
  double view_noise_scale = 1.0;    // on the per-view model's residual covariances
  double step_nees = 0.0;           // X's step under its own covariance (about 6 when the model explains it)
  double covariance_inflation = 1.0;  // in X's covariance, its factor for (s, a, b)'s own error (Kenward-Roger)
  PoseWithCovariance X;             // after the GLS step, with its covariance
  Matrix6d per_view_estimate_covariance = Matrix6d::Zero();  // the per-view X's covariance under the model
  PoseWithCovariance per_view_X;
  PoseWithCovariance per_view_pattern;  // Y, where the model is linearised
  Matrix6d per_view_cross_covariance = Matrix6d::Zero();
  /// The per-view model's own honesty check (calibrate_checked runs it too): its
  /// verdict and inflation (1 unless overconfident and inflate_when_overconfident).
  /// A check of new views from a file without `views` below predicts with the per-view
  /// model times it; with them, under the model (whose own honesty factor applies).
  std::string per_view_honesty;
  double per_view_inflation = 1.0;
  /// What a check of new views needs to predict them under the model (calibration_check.h),
  /// about the per-view X and Y: their joint covariance under the model, H0 C H0^T (X's
  /// block is per_view_estimate_covariance), and for each view the fit used, the
  /// effector's position and H0_j D_j, how the per-view estimate moves with that view's
  /// robot error: a new view's shared error is correlated with theirs.
  Matrix6d per_view_estimate_pattern_covariance = Matrix6d::Zero(), per_view_estimate_cross_covariance = Matrix6d::Zero();
  struct View {
    Eigen::Vector3d position = Eigen::Vector3d::Zero();          // m, the effector's, base frame
    Eigen::Matrix<double, 12, 6> gain = Eigen::Matrix<double, 12, 6>::Zero();  // H0_j D_j: (xi_X, xi_Y) per xi_E
    template <class Self, class Visit>
    static void fields(Self& s, Visit&& visit) {
      visit("position", s.position);
      visit("gain", s.gain);  // 12 x 6 row-major: (xi_X, xi_Y) in ROS order per the robot error xi_E
    }
  };
  std::vector<View> views;
  /// The per-view fit's own factors for its noise estimate's error, which the model's
  /// replaced in the calibration (not in files).
  double per_view_covariance_inflation = 1.0, per_view_pattern_covariance_inflation = 1.0;
  /// The model was given (SharedRobotErrorOptions::model), not chosen by BIC (not in files).
  bool given = false;

  bool fitted() const { return not_fitted.empty(); }
  bool chosen_fit() const { return fitted() && chosen; }
  bool used_fit() const { return fitted() && chosen && used; }
  template <class Self, class Visit>
  static void fields(Self& s, Visit&& visit) {
    visit("not_fitted", s.not_fitted, kWhenSet);
    visit("chosen", s.chosen, Only{s.fitted()});
    visit("used", s.used, Only{s.fitted(), true});  // files of earlier versions lack it: not used
    visit("bic_gain", s.bic_gain, Only{s.fitted()});
    visit("length_scale", s.length_scale, Only{s.chosen_fit()});
    visit("translation_sigma", s.translation_sigma, Only{s.chosen_fit()});
    visit("rotation_sigma", s.rotation_sigma, Only{s.chosen_fit()});
    visit("view_noise_scale", s.view_noise_scale, Only{s.chosen_fit()});
    visit("step_nees", s.step_nees, Only{s.chosen_fit()});
    visit("covariance_inflation", s.covariance_inflation, Only{s.chosen_fit()});
    visit("X", s.X, Only{s.chosen_fit()});
    visit("per_view_covariance_under_it", s.per_view_estimate_covariance, Only{s.chosen_fit()});
    // Used: the per-view model's X and Y with their own covariances, which the model's replaced.
    visit("per_view_X", s.per_view_X, Only{s.used_fit()});
    visit("per_view_pattern", s.per_view_pattern, Only{s.used_fit()});
    visit("per_view_cross_covariance", s.per_view_cross_covariance, Only{s.used_fit()});
    visit("per_view_honesty", s.per_view_honesty, Only{s.used_fit()});
    visit("per_view_inflation", s.per_view_inflation, Only{s.used_fit()});
    // What a check predicts new views with under the model (files of earlier versions lack them).
    visit("per_view_pattern_covariance_under_it", s.per_view_estimate_pattern_covariance, Only{s.used_fit(), true});
    visit("per_view_cross_covariance_under_it", s.per_view_estimate_cross_covariance, Only{s.used_fit(), true});
    visit("views", s.views, Only{s.used_fit(), true});
    visit("per_view_covariance_inflation", s.per_view_covariance_inflation, kInMemory);
    visit("per_view_pattern_covariance_inflation", s.per_view_pattern_covariance_inflation, kInMemory);
    visit("given", s.given, kInMemory);
  }
};

}  // namespace handeye
