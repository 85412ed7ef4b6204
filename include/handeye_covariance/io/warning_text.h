// A calibration's warnings and rejected samples in words (estimator.h Warning and
// Calibration::Rejected: a kind and its figures), as the result file, the summary, the
// report and /calibrate give them.
#pragma once

#include <string>
#include <vector>

#include "handeye_covariance/estimation/estimator.h"

namespace handeye {
namespace io {

std::string warning_text(const Warning& warning);
std::vector<std::string> warning_texts(const std::vector<Warning>& warnings);
/// Why a sample was left out, e.g. "its pattern pose is 9.12 sigma (Mahalanobis, 6 dof) ...".
std::string rejected_text(const Calibration::Rejected& rejected);

}  // namespace io
}  // namespace handeye
