// The prediction section of a calibration: calibration_check.h's prediction_check on
// the session's own views. Fields described once (core/fields.h).
#pragma once

#include "handeye_covariance/core/fields.h"

namespace handeye {

/// How well the noise model and the covariance predict a view the calibration has not
/// seen, measured on its own kept views by leave-one-out (calibration_check.h
/// prediction_check): each view predicted from the others' X, Y, covariance and noise
/// (estimated again without it). `scale` is the mean of d_i^2 / 6, d_i each view's
/// Mahalanobis length under its predicted covariance (1 when the model predicts
/// right); `dof` that mean's degrees of freedom from the d_i's own spread (6 n when
/// they scatter as chi2(6)). A check of new views (calibration_check.h) scales its
/// prediction by it.
struct PredictionRecord {
  double scale = 1.0;
  double dof = 0.0;
  int views = 0;
  template <class Self, class Visit>
  static void fields(Self& s, Visit&& visit) {
    visit("scale", s.scale);
    visit("dof", s.dof);
    visit("views", s.views, kOptional);
  }
};

}  // namespace handeye
