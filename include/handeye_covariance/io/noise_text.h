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

}  // namespace io
}  // namespace handeye
