// A calibration's noise model in words (the summary's and the result file's `noise.how`):
// the joint fit's model with its estimated numbers and the candidates it was chosen from,
// the shared robot error when used, or the corner fit's pixel noise.
#pragma once

#include <string>

#include "handeye_covariance/estimation/estimator.h"

namespace handeye {
namespace io {

/// Empty when nothing was estimated and no shared robot error is used (the noise as given,
/// pairs, or a calibration read from a file).
std::string noise_model_text(const Calibration& calibration);

/// Words the corner fit's figures into its `robot`, `target_points` and `pixel_noise`
/// (what files carry and the summary prints); the session calls it after the fit.
void word_corner_fit(CornerFitRecord& fit);

}  // namespace io
}  // namespace handeye
